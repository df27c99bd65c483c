// report/atomic_file: every file sidc writes appears whole or not at all, beside no stray
// temporary, with the mode a newly created file gets, and the old file intact on failure; devices
// and FIFOs are written through, never replaced; a link's target is replaced, not the link; a set
// of files appears together; leftovers of killed runs are removed, live temporaries are not.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <thread>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include "report/atomic_file.hpp"

namespace sidc {
namespace {

namespace fs = std::filesystem;

struct AtomicFile : ::testing::Test {
  fs::path dir;
  mode_t saved_mask = 0;
  void SetUp() override {
    saved_mask = ::umask(022);  // the writer reads the umask once per process: make it known
    dir = fs::temp_directory_path() / fs::path("sidc-atomic-" + std::to_string(::getpid()) + "-" +
                                              ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override {
    fs::remove_all(dir);
    ::umask(saved_mask);
  }
  std::string read(const fs::path& p) const {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
  std::size_t entries() const { return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator())); }
};

TEST_F(AtomicFile, WritesTheWholeContentAndLeavesNoTemporary) {
  std::string why;
  ASSERT_TRUE(write_file_atomically((dir / "a.txt").string(), std::string("one\ntwo\n"), &why)) << why;
  EXPECT_EQ(read(dir / "a.txt"), "one\ntwo\n");
  EXPECT_EQ(entries(), 1u);
}

TEST_F(AtomicFile, StreamsPieceByPiece) {
  std::string why;
  ASSERT_TRUE(write_file_atomically((dir / "rows.csv").string(), [](std::ostream& out) {
    for (int i = 0; i < 1000; ++i) out << i << "\n";
    return static_cast<bool>(out);
  }, &why)) << why;
  const std::string text = read(dir / "rows.csv");
  EXPECT_EQ(text.substr(0, 4), "0\n1\n");
  EXPECT_EQ(text.substr(text.size() - 4), "999\n");
}

TEST_F(AtomicFile, AnAbandonedOrThrowingWriteLeavesTheOldFileIntact) {
  std::string why;
  ASSERT_TRUE(write_file_atomically((dir / "f.json").string(), std::string("old"), &why));
  EXPECT_FALSE(write_file_atomically((dir / "f.json").string(), [](std::ostream& out) {
    out << "half";
    return false;
  }, &why));
  EXPECT_NE(why.find("cannot write `"), std::string::npos) << why;
  EXPECT_FALSE(write_file_atomically((dir / "f.json").string(), [](std::ostream& out) -> bool {
    out << "half";
    throw std::runtime_error("the writer failed");
  }, &why));
  EXPECT_EQ(read(dir / "f.json"), "old");
  EXPECT_EQ(entries(), 1u);  // no temporary left beside it
}

TEST_F(AtomicFile, AMissingFolderIsAReasonNamingTheFile) {
  std::string why;
  EXPECT_FALSE(write_file_atomically((dir / "no" / "such" / "x.csv").string(), std::string("x"), &why));
  EXPECT_NE(why.find("x.csv"), std::string::npos) << why;
  EXPECT_NE(why.find("No such file or directory"), std::string::npos) << why;
}

TEST_F(AtomicFile, TheFileGetsTheModeOfANewlyCreatedFile) {
  std::string why;
  ASSERT_TRUE(write_file_atomically((dir / "m.txt").string(), std::string("m"), &why)) << why;
  struct stat st {};
  ASSERT_EQ(::stat((dir / "m.txt").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0644u);  // 0666 less the umask 022, not mkstemp's private 0600
}


TEST_F(AtomicFile, ACharacterDeviceIsWrittenThroughNotReplaced) {
  if (::geteuid() != 0) GTEST_SKIP() << "making a device node needs root";
  const fs::path device = dir / "null";
  ASSERT_EQ(::mknod(device.c_str(), S_IFCHR | 0666, ::makedev(1, 3)), 0) << std::strerror(errno);  // as /dev/null
  std::string why;
  ASSERT_TRUE(write_file_atomically(device.string(), std::string("{}\n"), &why)) << why;
  struct stat st {};
  ASSERT_EQ(::lstat(device.c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode)) << "the device was replaced by a regular file";
  EXPECT_EQ(entries(), 1u);  // no temporary beside it
  EXPECT_TRUE(is_written_through("/dev/null"));
  EXPECT_TRUE(is_written_through("/dev/stdout"));
  EXPECT_FALSE(is_written_through((dir / "new.json").string()));
}

TEST_F(AtomicFile, AFullDeviceIsAWriteErrorNamingIt) {
  std::string why;
  EXPECT_FALSE(write_file_atomically("/dev/full", std::string(100000, 'x'), &why));
  EXPECT_NE(why.find("cannot write `/dev/full`: No space left on device"), std::string::npos) << why;
  struct stat st {};
  ASSERT_EQ(::stat("/dev/full", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
}

TEST_F(AtomicFile, AFifoIsWrittenThroughToItsReader) {
  const fs::path fifo = dir / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] { received = read(fifo); });
  std::string why;
  const bool written = write_file_atomically(fifo.string(), std::string("through the pipe\n"), &why);
  reader.join();
  EXPECT_TRUE(written) << why;
  EXPECT_EQ(received, "through the pipe\n");
  struct stat st {};
  ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  EXPECT_EQ(entries(), 1u);
}

TEST_F(AtomicFile, ALinksTargetIsReplacedAndTheLinkStays) {
  fs::create_directories(dir / "real");
  std::string why;
  ASSERT_TRUE(write_file_atomically((dir / "real" / "m.json").string(), std::string("old"), &why)) << why;
  fs::create_symlink("real/m.json", dir / "link.json");
  ASSERT_TRUE(write_file_atomically((dir / "link.json").string(), std::string("new"), &why)) << why;
  EXPECT_TRUE(fs::is_symlink(dir / "link.json"));
  EXPECT_EQ(read(dir / "real" / "m.json"), "new");
  EXPECT_EQ(entries(), 2u);  // the link and the folder: the temporary was made beside the target
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "real"), fs::directory_iterator()), 1);
}

TEST_F(AtomicFile, AFolderIsRefused) {
  fs::create_directories(dir / "out.json");
  std::string why;
  EXPECT_FALSE(write_file_atomically((dir / "out.json").string(), std::string("x"), &why));
  EXPECT_NE(why.find("Is a directory"), std::string::npos) << why;
  EXPECT_TRUE(fs::is_directory(dir / "out.json"));
}

TEST_F(AtomicFile, LeftoversOfKilledRunsGoLiveTemporariesStay) {
  std::ofstream(dir / ".fit.json.AbC123") << "killed run";
  std::ofstream(dir / ".fit.json.XyZ789") << "live run";
  std::ofstream(dir / ".other.json.AbC123") << "another name";
  const int live = ::open((dir / ".fit.json.XyZ789").c_str(), O_RDONLY);
  ASSERT_GE(live, 0);
  ASSERT_EQ(::flock(live, LOCK_EX), 0);  // as the run writing it holds it
  std::string why;
  ASSERT_TRUE(write_file_atomically((dir / "fit.json").string(), std::string("{}"), &why)) << why;
  EXPECT_FALSE(fs::exists(dir / ".fit.json.AbC123"));
  EXPECT_TRUE(fs::exists(dir / ".fit.json.XyZ789"));
  EXPECT_TRUE(fs::exists(dir / ".other.json.AbC123"));  // only this output's own leftovers
  ::close(live);
}

TEST_F(AtomicFile, ASetAppearsTogetherOrLeavesThePreviousFiles) {
  std::string why;
  {
    AtomicFileSet set;
    ASSERT_TRUE(set.add((dir / "fit.json").string(), std::string("fit 1"), &why)) << why;
    ASSERT_TRUE(set.add((dir / "validation.csv").string(), std::string("validation 1"), &why)) << why;
    EXPECT_FALSE(fs::exists(dir / "fit.json"));  // nothing appears before the commit
    ASSERT_TRUE(set.commit(&why)) << why;
  }
  {
    AtomicFileSet set;
    ASSERT_TRUE(set.add((dir / "fit.json").string(), std::string("fit 2"), &why)) << why;
    EXPECT_FALSE(set.add((dir / "validation.csv").string(), [](std::ostream& out) {
      out << "half";
      return false;
    }, &why));
  }  // abandoned: the first file's temporary goes too
  EXPECT_EQ(read(dir / "fit.json"), "fit 1");
  EXPECT_EQ(read(dir / "validation.csv"), "validation 1");
  EXPECT_EQ(entries(), 2u);
  {
    AtomicFileSet set;
    ASSERT_TRUE(set.add((dir / "fit.json").string(), std::string("fit 3"), &why)) << why;
    ASSERT_TRUE(set.commit(&why, {(dir / "validation.csv").string()})) << why;  // this run has none
  }
  EXPECT_EQ(read(dir / "fit.json"), "fit 3");
  EXPECT_FALSE(fs::exists(dir / "validation.csv"));
}

TEST_F(AtomicFile, AnOutputThatIsAnInputIsFoundThroughLinks) {
  std::ofstream(dir / "model.sid") << "model m";
  fs::create_symlink("model.sid", dir / "alias.json");
  const std::vector<std::string> inputs{(dir / "record.csv").string(), (dir / "model.sid").string()};
  EXPECT_EQ(input_overwritten_by((dir / "alias.json").string(), inputs), (dir / "model.sid").string());
  EXPECT_EQ(input_overwritten_by((dir / "." / "model.sid").string(), inputs), (dir / "model.sid").string());
  EXPECT_EQ(input_overwritten_by((dir / "new.json").string(), inputs), "");  // does not exist yet
  std::ofstream(dir / "other.json") << "x";
  EXPECT_EQ(input_overwritten_by((dir / "other.json").string(), inputs), "");
}

}  // namespace
}  // namespace sidc
