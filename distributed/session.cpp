// distributed/session.hpp: the processes of one command, over MPI when sidc was built with it.
#include "distributed/session.hpp"

#include "runtime/parallel_ranges.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <unistd.h>

#ifdef SIDC_HAVE_MPI
#include <mpi.h>
#endif

namespace sidc::distributed {
namespace {

std::unique_ptr<Session>& instance() {
  static std::unique_ptr<Session> session;
  return session;
}

#ifdef SIDC_HAVE_MPI
// True when a launcher (mpirun, srun) started this process as one rank of a job.
bool launched_as_rank() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"})
    if (std::getenv(name)) return true;
  return false;
}
#endif

}  // namespace

#ifdef SIDC_HAVE_MPI
// The rows' share over MPI: a status exchange, then a binary tree of merges to rank 0 (rank r
// takes r + 1, r + 2, r + 4, ... in that order: the same bits on every run), and the merged state
// broadcast back, so that every rank goes on with the state of all rows.
struct Session::Share final : RowShare {
  static constexpr int kMergeTag = 17;
  explicit Share(Session& s) : session(s) {}
  int part() const override { return session.rank_; }
  int parts() const override { return session.size_; }

  // Every collective's first step: the status exchange. Its outcome when the collective is not to
  // go on (a rank has left, or met a problem in its rows), nothing when it is.
  std::optional<Combined> statuses_say_stop(bool has_problem) {
    const std::vector<int> statuses = session.exchange(has_problem ? working_with_problem : working);
    if (session.someone_left_) return Combined{Outcome::stopped, session.who_left()};
    if (std::any_of(statuses.begin(), statuses.end(), [](int s) { return s == working_with_problem; })) return Combined{Outcome::problem, {}};
    return std::nullopt;
  }

  Combined merge(std::vector<double>& state, const Merge& merge_two, bool has_problem) override {
    if (auto stop = statuses_say_stop(has_problem)) return *stop;
    const int rank = session.rank_, size = session.size_;
    for (int step = 1; step < size; step *= 2) {
      if (rank % (2 * step) != 0) {  // hand this subtree's state up and leave the tree
        MPI_Send(state.data(), static_cast<int>(state.size()), MPI_DOUBLE, rank - step, kMergeTag, MPI_COMM_WORLD);
        break;
      }
      if (rank + step >= size) continue;
      MPI_Status status;
      MPI_Probe(rank + step, kMergeTag, MPI_COMM_WORLD, &status);
      int length = 0;
      MPI_Get_count(&status, MPI_DOUBLE, &length);
      std::vector<double> right(static_cast<std::size_t>(length));
      MPI_Recv(right.data(), length, MPI_DOUBLE, rank + step, kMergeTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      merge_two(state, right);  // the parts from rank + step on come right after this subtree's
    }
    long long length = static_cast<long long>(state.size());
    MPI_Bcast(&length, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
    state.resize(static_cast<std::size_t>(length));
    MPI_Bcast(state.data(), static_cast<int>(length), MPI_DOUBLE, 0, MPI_COMM_WORLD);
    return {Outcome::combined, {}};
  }

  // Part k's values broadcast from rank k, in pieces of at most 2^30 values (MPI counts are ints).
  void concatenate(std::span<const double> mine, std::span<double> all, std::span<const std::size_t> lengths) override {
    constexpr std::size_t kPiece = std::size_t{1} << 30;
    std::size_t offset = 0;
    for (int k = 0; k < session.size_; ++k) {
      const std::size_t length = lengths[static_cast<std::size_t>(k)];
      if (k == session.rank_) std::copy(mine.begin(), mine.end(), all.begin() + static_cast<std::ptrdiff_t>(offset));
      for (std::size_t done = 0; done < length; done += kPiece)
        MPI_Bcast(all.data() + offset + done, static_cast<int>(std::min(kPiece, length - done)), MPI_DOUBLE, k, MPI_COMM_WORLD);
      offset += length;
    }
  }

  Combined sum(std::span<double> values, bool has_problem) override {
    if (auto stop = statuses_say_stop(has_problem)) return *stop;
    MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    return {Outcome::combined, {}};
  }

  Session& session;
};

Session& Session::start(int& argc, char**& argv) {
  auto& session = instance();
  session.reset(new Session());
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  if (!launched_as_rank()) return *session;
  int provided = 0;
  // Only the main thread talks to MPI; the fold's own threads never do.
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  session->mpi_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &session->rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &session->size_);
  MPI_Comm node;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, session->rank_, MPI_INFO_NULL, &node);
  int on_node = 1;
  MPI_Comm_size(node, &on_node);
  MPI_Comm_free(&node);
  // The node's cores divided among its ranks, and never more than this rank may run on: mpirun binds
  // each rank to one core by default when it starts at most two (`--bind-to none` frees them).
  const unsigned share = std::max(1u, cores / static_cast<unsigned>(std::max(on_node, 1)));
  session->threads_per_rank_ = std::min(static_cast<int>(share), core_count());  // core_count: the affinity mask's
  if (session->size_ > 1) session->share_ = new Share(*session);
  if (session->rank_ > 0) {
    // Nothing on stdout; stderr held in an unnamed file until finish() decides whether to show it.
    std::fflush(stdout);
    if (std::FILE* null = std::freopen("/dev/null", "w", stdout); !null) std::fclose(stdout);
    if (std::FILE* held = std::tmpfile()) {
      std::fflush(stderr);
      session->real_stderr_ = dup(STDERR_FILENO);
      session->held_stderr_ = dup(fileno(held));
      dup2(session->held_stderr_, STDERR_FILENO);
      std::fclose(held);
    }
  }
  return *session;
}

std::vector<int> Session::exchange(Status mine) {
  std::vector<int> mine_only(static_cast<std::size_t>(size_), -1), statuses(static_cast<std::size_t>(size_), -1);
  mine_only[static_cast<std::size_t>(rank_)] = mine;
  MPI_Allreduce(mine_only.data(), statuses.data(), size_, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  last_statuses_ = statuses;
  if (mine >= finished_ok) left_ = true;  // no further exchange from this rank
  for (std::size_t r = 0; r < statuses.size(); ++r)
    if (static_cast<int>(r) != rank_ && statuses[r] >= finished_ok) someone_left_ = true;
  return statuses;
}

Session::~Session() {
  delete share_;
}

int Session::finish(int my_code) {
  if (!mpi_) return my_code;
  bool show_held = false;
  if (!someone_left_ && !left_) {
    const std::vector<int> statuses = exchange(my_code == 0 ? finished_ok : finished_failed);
    // Shown when rank 0 did not fail: rank 0 then names this rank, and its error is only here.
    show_held = my_code != 0 && rank_ > 0 && statuses[0] != finished_failed;
    if (my_code == 0 && std::any_of(statuses.begin(), statuses.end(), [](int s) { return s == finished_failed; })) my_code = 1;
  } else {
    show_held = my_code != 0 && rank_ > 0 && last_statuses_[0] != finished_failed;
  }
  if (rank_ > 0 && real_stderr_ >= 0) {
    std::fflush(stderr);
    if (show_held && held_stderr_ >= 0) {
      std::string text;
      char buffer[4096];
      lseek(held_stderr_, 0, SEEK_SET);
      for (ssize_t got; (got = read(held_stderr_, buffer, sizeof buffer)) > 0;) text.append(buffer, static_cast<std::size_t>(got));
      std::string shown;
      for (std::size_t begin = 0; begin < text.size();) {
        const std::size_t end = std::min(text.find('\n', begin), text.size());
        shown += fmt::format("[rank {}] {}\n", rank_, text.substr(begin, end - begin));
        begin = end + 1;
      }
      if (write(real_stderr_, shown.data(), shown.size()) < 0) my_code = my_code ? my_code : 1;
    }
  }
  // Collective: a rank that left earlier waits in its own MPI_Finalize for the others.
  MPI_Finalize();
  return my_code;
}

bool Session::agree(int my_code) {
  if (!mpi_ || size_ == 1) return my_code == 0;
  if (someone_left_) return false;
  // Not a finish: a rank that failed is in its finish() and meets this exchange there.
  const std::vector<int> statuses = exchange(my_code == 0 ? working : finished_failed);
  if (my_code != 0) return false;
  return std::none_of(statuses.begin(), statuses.end(), [](int s) { return s >= finished_ok; });
}
#else
struct Session::Share {};

namespace {
// A launcher's size and rank, read from the environment it sets (Open MPI, PMIx, PMI).
int launched_number(std::initializer_list<const char*> names, int otherwise) {
  for (const char* name : names)
    if (const char* value = std::getenv(name)) return std::atoi(value);
  return otherwise;
}
}  // namespace

Session& Session::start(int&, char**&) {
  instance().reset(new Session());
  Session& session = *instance();
  const int size = launched_number({"OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "PMI_SIZE"}, 1);
  if (size > 1) {
    session.rank_ = launched_number({"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"}, 0);
    session.launch_problem_ = fmt::format(
        "this sidc was built without MPI, and a launcher started {} copies of it: each would fit alone and write the same files", size);
  }
  return session;
}
std::vector<int> Session::exchange(Status) { return {}; }
Session::~Session() = default;
int Session::finish(int my_code) { return my_code; }
bool Session::agree(int my_code) { return my_code == 0; }
#endif

Session& Session::current() {
  if (!instance()) {
    int argc = 0;
    char** argv = nullptr;
    return start(argc, argv);
  }
  return *instance();
}

RowShare* Session::row_share() {
#ifdef SIDC_HAVE_MPI
  return share_;
#else
  return nullptr;
#endif
}

std::string Session::who_left() const {
  std::string ranks;
  for (std::size_t r = 0; r < last_statuses_.size(); ++r)
    if (static_cast<int>(r) != rank_ && last_statuses_[r] >= finished_ok)
      ranks += (ranks.empty() ? "" : ", ") + std::to_string(r);
  const std::string first = ranks.substr(0, ranks.find(','));
  return fmt::format("{} {} of the {} MPI processes stopped with an error (its lines on stderr begin with [rank {}]); "
                     "the job stops without writing any file", first == ranks ? "rank" : "ranks", ranks, size_, first);
}

std::string Session::processes_line() const {
  if (size_ <= 1) return {};
  return fmt::format("processes: {} MPI ranks of {} thread{} each; each parses its byte range of every record, they share the rows "
                     "of every streamed design and the weak form's integrals, and each evaluates smaller designs whole (docs/distributed.md)",
                     size_, threads_per_rank_, threads_per_rank_ == 1 ? "" : "s");
}

}  // namespace sidc::distributed
