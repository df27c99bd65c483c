// The processes one sidc command runs as (issue 17): one, or the ranks mpirun started.
//
// Under `mpirun -np N sidc fit ...` every rank runs the same command on the same records; the rows
// of each streamed group are shared among them (runtime/solve/row_share.hpp) and rank 0 alone
// prints the report and writes files. Started any other way, or built without MPI, sidc is one
// process and behaves exactly as without this layer.
//
// Relies on: MPI (Open MPI from Debian) when CMake found it (SIDC_HAVE_MPI), nothing otherwise.
// Guarantees:
// - start() initialises MPI only when the environment says a launcher started this process
//   (OMPI_COMM_WORLD_SIZE, PMIX_RANK or PMI_RANK set): a plain `sidc fit` never touches MPI.
// - Every collective step (RowShare::combine, finish) begins with one exchange of every rank's
//   status, so a rank that fails anywhere ends its run with finish(), which meets whatever step
//   the others are in: they learn it there and stop with "rank k stopped" instead of waiting for
//   it. A job therefore never hangs on a failed rank, and rank 0 writes no file unless every rank
//   reached finish() without an error (fit_command asks agree() before writing).
// - Ranks above 0 print nothing on stdout; their stderr is held back, and shown (each line
//   prefixed with the rank) only when they failed and rank 0 did not, so that an error met by
//   every rank is printed once.
#pragma once

#include <string>
#include <vector>

#include "runtime/solve/row_share.hpp"

namespace sidc::distributed {

class Session {
 public:
  // Once, first thing in main(). argc/argv as main got them (MPI may read them).
  static Session& start(int& argc, char**& argv);
  static Session& current();  // after start()

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool is_writer() const { return rank_ == 0; }  // prints and writes files
  // Threads each rank uses for its share: the cores of its node divided among the ranks on it.
  int threads_per_rank() const { return threads_per_rank_; }
  // Non-empty when a launcher started several copies of a sidc built without MPI: each would fit
  // alone and write the same files, so the command line refuses to start (rank 0 says why).
  const std::string& launch_problem() const { return launch_problem_; }
  // The report's line naming the processes; empty for one process.
  std::string processes_line() const;
  // The rows' share among the ranks; null for one process.
  RowShare* row_share();

  // Before writing outputs: true when no rank has failed so far (collective; every rank calls it
  // at the same point). `my_code` is this rank's exit code so far.
  bool agree(int my_code);
  // Why the job stopped, after agree() returned false or a RowShare said `stopped`.
  std::string who_left() const;
  // The last call on every rank: exchanges exit codes (unless a rank already left), shows a held
  // error when this rank alone failed, finalises MPI, and returns the code to exit with.
  int finish(int my_code);

  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  ~Session();

 private:
  // One status exchange (every collective step starts with one): every rank's status, by rank.
  enum Status : int { working = 0, working_with_problem = 1, finished_ok = 2, finished_failed = 3 };
  std::vector<int> exchange(Status mine);

  Session() = default;
  int rank_ = 0, size_ = 1, threads_per_rank_ = 0;
  bool mpi_ = false;
  bool someone_left_ = false;  // another rank has made its last exchange
  bool left_ = false;          // this rank has made its last exchange
  std::vector<int> last_statuses_;
  std::string launch_problem_;
  int held_stderr_ = -1, real_stderr_ = -1;  // ranks above 0: the file their stderr goes to, and the terminal's
  struct Share;
  Share* share_ = nullptr;
};

}  // namespace sidc::distributed
