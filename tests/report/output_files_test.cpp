// What sidc reads and writes, through the binary (issue 19): a device or FIFO named as an output is
// written through, never replaced; an output that is one of the run's inputs is refused before any
// work; a failed `fit --out DIR` leaves the previous run's files as they were, and leftovers of a
// killed run are removed; a FIFO or /dev/zero named as an input is refused at once; a write error
// on standard output (a full disk, a closed pipe) is exit 1 with a message.
//
// Relies on: the sidc binary (SIDC_BINARY), a work folder (SIDC_OUTPUT_FILES_WORK_DIR), /dev/full.
// The device-node test needs root and is skipped otherwise.
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "support/shell.hpp"

extern char** environ;

namespace sidc {
namespace {

namespace fs = std::filesystem;
using sidc::testing::read_text;
using sidc::testing::shell_quoted;

using SidcRun = sidc::testing::CommandRun;

// A fresh folder of the running test's own (ctest runs the tests as parallel processes), holding
// a first-order model and a record it fits exactly (y = exp(-2t): a = 2).
fs::path work() {
  const fs::path dir = fs::path(SIDC_OUTPUT_FILES_WORK_DIR) / ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "decay.sid") << "model decay\noutput y\nparam a\ndata \"record.csv\"\ny' + a*y = 0\n";
  std::ofstream record(dir / "record.csv");
  record << "t,y\n";
  for (int i = 0; i <= 200; ++i) record << i * 0.01 << "," << std::exp(-2 * i * 0.01) << "\n";
  return dir;
}

// Runs `sidc ARGUMENTS` in `dir` (a 20 s limit: a hang fails rather than blocks the suite).
SidcRun run_sidc(const fs::path& dir, const std::string& arguments, const std::string& stdout_to = "") {
  return sidc::testing::run_captured("cd " + shell_quoted(dir) + " && timeout 20 " + shell_quoted(SIDC_BINARY) + " " + arguments,
                                     dir / "stdout.txt", dir / "stderr.txt", stdout_to);
}

std::size_t temporaries_in(const fs::path& dir) {
  std::size_t n = 0;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().filename().string().starts_with(".")) ++n;
  return n;
}

TEST(OutputFiles, ADeviceNamedAsTheOutputIsWrittenThrough) {
  const fs::path dir = work();
  const SidcRun to_null = run_sidc(dir, "compile decay.sid -o /dev/null");
  EXPECT_EQ(to_null.status, 0) << to_null.err;
  struct stat st {};
  ASSERT_EQ(::stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  const SidcRun to_stdout = run_sidc(dir, "compile decay.sid -o /dev/stdout");
  EXPECT_EQ(to_stdout.status, 0) << to_stdout.err;
  EXPECT_NE(to_stdout.out.find("\"format\": \"sidc-compiled-model\""), std::string::npos) << to_stdout.out;
  EXPECT_TRUE(fs::is_regular_file(dir / "stdout.txt"));
  if (::geteuid() != 0) GTEST_SKIP() << "making a device node needs root";
  ASSERT_EQ(::mknod((dir / "null").c_str(), S_IFCHR | 0666, ::makedev(1, 3)), 0) << std::strerror(errno);
  const SidcRun to_device = run_sidc(dir, "compile decay.sid -o null");
  EXPECT_EQ(to_device.status, 0) << to_device.err;
  ASSERT_EQ(::lstat((dir / "null").c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode)) << "the device node was replaced by a regular file";
  EXPECT_EQ(temporaries_in(dir), 0u);
}

TEST(OutputFiles, AnOutputThatIsAnInputIsRefusedBeforeAnyWork) {
  const fs::path dir = work();
  const std::string model = read_text(dir / "decay.sid"), record = read_text(dir / "record.csv");
  const SidcRun compile = run_sidc(dir, "compile decay.sid -o ./decay.sid");
  EXPECT_EQ(compile.status, 2);
  EXPECT_EQ(compile.err, "error: output `./decay.sid` is `decay.sid`, an input of this run: writing it would destroy it\n"
                         "hint: choose another output path\n");
  const SidcRun report = run_sidc(dir, "fit decay.sid --report record.csv");
  EXPECT_EQ(report.status, 2);
  EXPECT_NE(report.err.find("output `record.csv` is `record.csv`, an input of this run"), std::string::npos) << report.err;
  EXPECT_EQ(report.out, "");  // refused before the fit
  fs::create_directories(dir / "out");
  fs::create_symlink("../record.csv", dir / "out" / "residuals.csv");
  const SidcRun out = run_sidc(dir, "fit decay.sid --out out");
  EXPECT_EQ(out.status, 2);
  EXPECT_NE(out.err.find("output `out/residuals.csv` is `record.csv`, an input of this run"), std::string::npos) << out.err;
  EXPECT_EQ(read_text(dir / "decay.sid"), model);
  EXPECT_EQ(read_text(dir / "record.csv"), record);
}

TEST(OutputFiles, AFailedFitKeepsThePreviousRunsFiles) {
  const fs::path dir = work();
  const SidcRun first = run_sidc(dir, "fit decay.sid --out out");
  ASSERT_EQ(first.status, 0) << first.err;
  const std::string fit_json = read_text(dir / "out" / "fit.json");
  ASSERT_NE(fit_json.find("\"sidc-fit\""), std::string::npos);
  // The second run cannot write residuals.csv (a folder stands there): its fit.json must not replace
  // the first run's, and none of its temporaries may stay.
  fs::remove(dir / "out" / "residuals.csv");
  fs::create_directories(dir / "out" / "residuals.csv");
  const SidcRun second = run_sidc(dir, "fit decay.sid --out out --from 0.5");
  EXPECT_EQ(second.status, 1);
  EXPECT_NE(second.err.find("cannot write `out/residuals.csv`: Is a directory"), std::string::npos) << second.err;
  EXPECT_EQ(read_text(dir / "out" / "fit.json"), fit_json);
  EXPECT_TRUE(fs::exists(dir / "out" / "validation.csv"));
  EXPECT_EQ(temporaries_in(dir / "out"), 0u);
  // A run without validation removes the earlier validation.csv: it would read as this fit's.
  fs::remove(dir / "out" / "residuals.csv");
  const SidcRun third = run_sidc(dir, "fit decay.sid --out out --no-validate");
  EXPECT_EQ(third.status, 0) << third.err;
  EXPECT_TRUE(fs::exists(dir / "out" / "residuals.csv"));
  EXPECT_FALSE(fs::exists(dir / "out" / "validation.csv"));
}

TEST(OutputFiles, LeftoversOfAKilledRunAreRemovedByTheNext) {
  const fs::path dir = work();
  fs::create_directories(dir / "out");
  std::ofstream(dir / "out" / ".fit.json.AbC123") << "{\"half\":";
  std::ofstream(dir / "out" / ".residuals.csv.XyZ789") << "group,equ";
  const SidcRun run = run_sidc(dir, "fit decay.sid --out out");
  EXPECT_EQ(run.status, 0) << run.err;
  EXPECT_EQ(temporaries_in(dir / "out"), 0u);
}

TEST(OutputFiles, AFifoOrADeviceAsAnInputIsRefusedAtOnce) {
  const fs::path dir = work();
  ASSERT_EQ(::mkfifo((dir / "fifo.sid").c_str(), 0600), 0);
  const SidcRun fifo = run_sidc(dir, "compile fifo.sid");  // no writer: an ordinary open would block forever
  EXPECT_EQ(fifo.status, 1);
  EXPECT_EQ(fifo.err, "error: cannot read `fifo.sid`: it is a FIFO, not a regular file\n"
                      "hint: give the path of a model file, e.g. `sidc compile examples/thesis-4-1/quasi_linear.sid`\n");
  const SidcRun zero_model = run_sidc(dir, "compile /dev/zero");
  EXPECT_EQ(zero_model.status, 1);
  EXPECT_NE(zero_model.err.find("error: cannot read `/dev/zero`: it is a character device, not a regular file"), std::string::npos) << zero_model.err;
  const SidcRun zero = run_sidc(dir, "fit decay.sid --data /dev/zero");
  EXPECT_EQ(zero.status, 1);
  EXPECT_NE(zero.err.find("data file `/dev/zero` is a character device, not a regular file"), std::string::npos) << zero.err;
}

TEST(OutputFiles, AWriteErrorOnStandardOutputIsExit1) {
  const fs::path dir = work();
  const SidcRun full = run_sidc(dir, "compile decay.sid --dump=normalized", "/dev/full");
  EXPECT_EQ(full.status, 1);
  EXPECT_NE(full.err.find("error: cannot write standard output: No space left on device"), std::string::npos) << full.err;
  // A closed pipe: the reading end closed before sidc starts, so the first write fails (EPIPE).
  int fds[2];
  ASSERT_EQ(::pipe2(fds, O_CLOEXEC), 0);
  ::close(fds[0]);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_addopen(&actions, 2, (dir / "stderr.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const std::string model = (dir / "decay.sid").string();
  std::string program = SIDC_BINARY, command = "compile", dump = "--dump=normalized", path = model;
  char* argv[] = {program.data(), command.data(), dump.data(), path.data(), nullptr};
  pid_t pid = 0;
  ASSERT_EQ(::posix_spawn(&pid, program.c_str(), &actions, nullptr, argv, environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 1);
  EXPECT_NE(read_text(dir / "stderr.txt").find("error: cannot write standard output: Broken pipe"), std::string::npos) << read_text(dir / "stderr.txt");
}

}  // namespace
}  // namespace sidc
