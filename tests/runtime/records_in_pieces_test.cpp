// read_csv piece by piece (CsvOptions::chunk_bytes) against the same file read whole: the same
// record (names, header line, every value's bits, the faults kept, each row's line) or the same
// diagnostic, for every record file of the project (the flawed-file catalogue included) and for
// texts made here to put a piece's end everywhere: CRLF and CR line ends, comments and blank lines
// between rows, a byte-order mark, spreadsheet rows of empty cells, faulty cells late in the file,
// a NUL byte after a bad row, a last line without its line end; pieces of 1 byte to larger than the
// file, on one thread and (parallel_above_bytes small) on two within each piece. And the same file
// read by 2, 3 and 5 parts (CsvOptions::share; threads here, MPI ranks under mpirun), each its own
// byte range: every part ends with the same record, or the same diagnostic, as one reader alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include <unistd.h>

#include "runtime/records/records.hpp"
#include "support/thread_share.hpp"

namespace sidc {
namespace {

namespace fs = std::filesystem;

std::string describe(const std::variant<Record, Diagnostic>& result) {
  if (const auto* d = std::get_if<Diagnostic>(&result)) return "diagnostic: " + render(*d);
  const Record& r = std::get<Record>(result);
  std::string out = "header line " + std::to_string(r.header_line) + ", " + std::to_string(r.rows()) + " rows\n";
  for (std::size_t c = 0; c < r.names.size(); ++c) {
    out += r.names[c] + ":";
    for (double v : r.columns[c]) out += " " + std::to_string(std::bit_cast<std::uint64_t>(v));
    out += "\n  faults:";
    for (const auto& f : r.first_faults[c]) out += " (" + std::to_string(f.row) + " " + std::to_string(static_cast<int>(f.fault)) + " " + f.text + ")";
    out += "\n";
  }
  out += "lines:";
  for (std::size_t row = 0; row < r.rows(); ++row) out += " " + std::to_string(r.line_of_row(row));
  return out;
}

void expect_same_in_pieces(const std::string& path) {
  CsvOptions whole;
  whole.chunk_bytes = 0;
  const std::string expected = describe(read_csv(path, whole));
  const auto size = fs::file_size(path);
  for (const std::size_t chunk : {std::size_t{1}, std::size_t{2}, std::size_t{3}, std::size_t{7}, std::size_t{64}, std::size_t{1000}}) {
    if (chunk >= size && chunk != 1000) continue;
    for (const std::size_t parallel : {std::numeric_limits<std::size_t>::max(), std::size_t{16}}) {
      CsvOptions pieces;
      pieces.chunk_bytes = chunk;
      pieces.parallel_above_bytes = parallel;
      ASSERT_EQ(describe(read_csv(path, pieces)), expected) << path << ", pieces of " << chunk << " bytes, parallel above " << parallel;
    }
  }
}

// Every part's record (described) when `parts` parts read the file together in pieces of `chunk` bytes.
std::vector<std::string> read_by_parts(const std::string& path, int parts, std::size_t chunk) {
  ThreadRoom room(parts);
  return in_parts(room, [&](RowShare& share, int) {
    CsvOptions o;
    o.chunk_bytes = chunk;
    o.share = &share;
    return describe(read_csv(path, o));
  });
}

void expect_same_by_parts(const std::string& path) {
  CsvOptions whole;
  whole.chunk_bytes = 0;
  const std::string expected = describe(read_csv(path, whole));
  for (const int parts : {2, 3, 5})
    for (const std::size_t chunk : {std::size_t{1}, std::size_t{7}, std::size_t{1000}}) {
      const auto results = read_by_parts(path, parts, chunk);
      for (std::size_t k = 0; k < results.size(); ++k)
        ASSERT_EQ(results[k], expected) << path << ": part " << k << " of " << parts << ", pieces of " << chunk << " bytes";
    }
}

TEST(RecordsInPieces, EveryRecordFileOfTheProjectReadsTheSame) {
  std::size_t files = 0;
  for (const char* folder : {"/tests/data/bad", "/tests/runtime/data", "/examples"}) {
    for (const auto& entry : fs::recursive_directory_iterator(std::string(SIDC_SOURCE_DIR) + folder)) {
      const auto ext = entry.path().extension();
      if (!entry.is_regular_file() || (ext != ".csv" && ext != ".tsv" && ext != ".txt") || fs::file_size(entry.path()) > (1u << 18)) continue;
      SCOPED_TRACE(entry.path().string());
      expect_same_in_pieces(entry.path().string());
      expect_same_by_parts(entry.path().string());
      ++files;
    }
  }
  EXPECT_GT(files, 30u);
}

class TextFile {
 public:
  explicit TextFile(const std::string& text) {
    path_ = (fs::temp_directory_path() / ("sidc_pieces_" + std::to_string(counter_++) + "_" + std::to_string(::getpid()) + ".csv")).string();
    std::ofstream(path_, std::ios::binary) << text;
  }
  ~TextFile() { fs::remove(path_); }
  const std::string& path() const { return path_; }

 private:
  static inline int counter_ = 0;
  std::string path_;
};

TEST(RecordsInPieces, TextsThatPutAPieceEndOrAPartBoundaryEverywhere) {
  const std::vector<std::string> texts = {
      "t,x,y\n0,1,2\n1,2,3\n2,3,4\n3,4,5\n4,5,6\n",
      "t,x,y\r\n0,1,2\r\n1,2,3\r\n2,3,4\r\n",                                  // CRLF
      "t,x,y\r0,1,2\r1,2,3\r2,3,4\r",                                          // CR only
      "\xEF\xBB\xBF# comment\n\n\"t\",\"x\"\n# between\n0,1\n\n1,2\n,\n2,3\n",  // BOM, comments, blank and empty rows
      "t;x\n0;1,5\n1;2,5\n",                                                   // semicolons and decimal commas
      "t,x\n0,1\n1,abc\n2,\n3,nan\n4,1e999\n5,6\n",                            // faults late
      "t,x\n0,1\n1,2\n2,3,4\n3,4\n",                                           // too many fields
      "t,x\n0,1\n1,2\n2\n3,4\n",                                               // too few fields
      std::string("t,x\n0,1\n1,2,3\n2,3\n3,\0\n", 22),                         // a bad row, then a NUL byte
      "t,x\n0,1\n1,2\n2,3",                                                    // no line end at the end
      "\n\n# only comments\n#\n\n",                                            // nothing
      "t,x\n",                                                                 // a header alone
      "0 1 2\n1  2\t3\n 2 3 4 \n",                                             // blanks, no header
      "t,x,\n0,1,\n1,2,\n",                                                    // trailing separators
  };
  for (std::size_t k = 0; k < texts.size(); ++k) {
    SCOPED_TRACE(k);
    const TextFile file(texts[k]);
    expect_same_in_pieces(file.path());
    expect_same_by_parts(file.path());
  }
}

// Pieces of 1 MiB and more are read ahead on a thread while the one before is parsed (read_rows):
// texts of a few MB, clean and with a late fault, a late bad row, a late NUL byte, CRLF ends.
TEST(RecordsInPieces, LargePiecesReadAheadAsTheWholeFileReads) {
  std::string rows;
  for (int i = 0; i < 80000; ++i) rows += std::to_string(i) + "," + std::to_string(i * 0.001) + "," + std::to_string(i % 97) + "\n";
  const std::size_t late = rows.size() - 1000;
  const std::size_t late_line = rows.find('\n', late) + 1;  // a line start near the end
  std::vector<std::string> texts = {"t,x,y\n" + rows};
  texts.push_back("t,x,y\n" + rows.substr(0, late_line) + "7,abc,8\n" + rows.substr(late_line));     // a faulty cell
  texts.push_back("t,x,y\n" + rows.substr(0, late_line) + "7,8\n" + rows.substr(late_line));         // too few fields
  texts.push_back("t,x,y\n" + rows.substr(0, late_line) + std::string("7,\0,8\n", 6) + rows.substr(late_line));  // a NUL byte
  std::string crlf = "t,x,y\r\n";
  for (std::size_t i = 0, j; i < rows.size(); i = j + 1) {
    j = rows.find('\n', i);
    crlf += rows.substr(i, j - i) + "\r\n";
  }
  texts.push_back(crlf);
  for (std::size_t k = 0; k < texts.size(); ++k) {
    SCOPED_TRACE(k);
    const TextFile file(texts[k]);
    CsvOptions whole;
    whole.chunk_bytes = 0;
    const std::string expected = describe(read_csv(file.path(), whole));
    for (const std::size_t chunk : {std::size_t{1} << 20}) {
      CsvOptions pieces;
      pieces.chunk_bytes = chunk;
      EXPECT_EQ(describe(read_csv(file.path(), pieces)), expected) << "pieces of " << chunk << " bytes";
      for (const int parts : {2, 3})
        for (const auto& result : read_by_parts(file.path(), parts, chunk)) EXPECT_EQ(result, expected) << parts << " parts";
    }
  }
}

TEST(RecordsInPieces, ProgressHearsEachPieceUpToTheWholeFile) {
  std::string text = "t,x\n";
  for (int i = 0; i < 1000; ++i) text += std::to_string(i) + "," + std::to_string(i * 0.5) + "\n";
  const TextFile file(text);
  std::vector<std::size_t> heard;
  CsvOptions pieces;
  pieces.chunk_bytes = 512;
  pieces.progress = [&](std::size_t done, std::size_t total) {
    EXPECT_EQ(total, text.size());
    heard.push_back(done);
  };
  ASSERT_TRUE(std::holds_alternative<Record>(read_csv(file.path(), pieces)));
  ASSERT_GT(heard.size(), 5u);
  EXPECT_TRUE(std::is_sorted(heard.begin(), heard.end()));
  EXPECT_EQ(heard.back(), text.size());
  heard.clear();
  pieces.chunk_bytes = 0;  // read whole: nothing to hear
  ASSERT_TRUE(std::holds_alternative<Record>(read_csv(file.path(), pieces)));
  EXPECT_TRUE(heard.empty());
}

TEST(RecordsInPieces, RandomTexts) {
  const std::string alphabet = "0123456789.,;\t \n\r\"#eE+-nai";
  std::mt19937 rng(20261127);
  for (int trial = 0; trial < 300; ++trial) {
    std::string text = "t,x,y\n";
    text.resize(6 + rng() % 120, ' ');
    for (std::size_t i = 6; i < text.size(); ++i) text[i] = alphabet[rng() % alphabet.size()];
    const TextFile file(text);
    SCOPED_TRACE(text);
    expect_same_in_pieces(file.path());
    expect_same_by_parts(file.path());
  }
}

}  // namespace
}  // namespace sidc
