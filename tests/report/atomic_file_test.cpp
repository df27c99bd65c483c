// report/atomic_file: every file sidc writes appears whole or not at all, beside no stray
// temporary, with the mode a newly created file gets, and the old file intact on failure.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <sys/stat.h>

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

}  // namespace
}  // namespace sidc
