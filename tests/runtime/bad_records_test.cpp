// The catalogue of flawed records in tests/data/bad (see its README.md): each file is read the way
// the runtime reads a record for a model with time `t`, output `y` and input `x` (read_csv, then
// complete_column for t, y, x, then uniform_step on t), and the first diagnostic must have the
// expected code, file, row, column and key phrase.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <set>
#include <string>
#include <thread>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "diagnostics/regular_file.hpp"
#include "runtime/records/records.hpp"
#include "runtime/records/sampling.hpp"

namespace sidc {
namespace {

const std::string kBad = std::string(SIDC_SOURCE_DIR "/tests/data/bad/");

struct BadRecord {
  const char* file;
  const char* code;
  int row;
  int column;
  const char* phrase;  // must occur in the message or the hint
};

const BadRecord kCatalogue[] = {
    {"nan_cell.csv", "data-nan-cell", 5, 2, "is NaN"},
    {"inf_cell.csv", "data-infinite-cell", 4, 3, "`-inf`"},
    {"empty_cell.csv", "data-empty-cell", 6, 2, "empty cell in column `y`"},
    {"empty_time_cell.csv", "data-empty-cell", 5, 1, "empty cell in column `t`"},
    {"non_numeric_cell.csv", "data-non-numeric-cell", 4, 2, "`0.00 mm` in column `y` is not a number"},
    {"out_of_range.csv", "data-out-of-range-cell", 4, 3, "beyond the range of a double"},
    {"thousands_separator.csv", "data-too-many-fields", 4, 4, "more fields than the 3 columns"},
    {"too_many_fields.csv", "data-too-many-fields", 5, 4, "more fields than the 3 columns"},
    {"too_few_fields.csv", "data-too-few-fields", 4, 3, "row has 2 fields but the header has 3"},
    {"tab_mixup.tsv", "data-too-few-fields", 4, 3, "a run of spaces and tabs is one separator"},
    {"nonuniform_step.csv", "data-time-step-not-uniform", 6, 1, "--resample"},
    {"time_backwards.csv", "data-time-backwards", 6, 1, "goes backwards, from 0.03 to 0.02"},
    {"duplicate_time.csv", "data-time-repeats", 5, 1, "repeats the previous row"},
    {"header_only.csv", "data-no-rows", 2, 1, "no data rows"},
    {"empty.csv", "data-empty-file", 1, 1, "holds no data"},
    {"comments_only.csv", "data-empty-file", 1, 1, "holds no data"},
    {"binary_garbage.csv", "data-binary-file", 1, 41, "not text"},
    {"utf16.csv", "data-binary-file", 1, 4, "saved as UTF-8"},
    {"duplicate_column.csv", "data-duplicate-column", 2, 4, "duplicate column name `y` (first used in column 2)"},
    {"unterminated_quote.csv", "data-unterminated-quote", 2, 3, "unterminated quote"},
    {"missing_column.csv", "data-unknown-column", 2, 1, "no column named `x` (columns: t, y, u)"},
    {"decimal_comma.csv", "data-decimal-comma", 3, 1, "decimal-comma option"},
};

// The first problem the runtime would meet with this file.
std::optional<Diagnostic> first_problem(const std::string& path) {
  auto record = read_csv(path);
  if (auto* d = std::get_if<Diagnostic>(&record)) return *d;
  const Record& r = std::get<Record>(record);
  for (const char* name : {"t", "y", "x"}) {
    auto column = complete_column(r, name);
    if (auto* d = std::get_if<Diagnostic>(&column)) return *d;
  }
  auto step = uniform_step(r, "t");
  if (auto* d = std::get_if<Diagnostic>(&step)) return *d;
  return std::nullopt;
}

class BadRecordTest : public ::testing::TestWithParam<BadRecord> {};

TEST_P(BadRecordTest, NamesFileRowColumnAndCause) {
  const BadRecord& expected = GetParam();
  const std::string path = kBad + expected.file;
  ASSERT_TRUE(std::filesystem::exists(path)) << path;
  const auto d = first_problem(path);
  ASSERT_TRUE(d.has_value()) << expected.file << " was accepted";
  EXPECT_EQ(d->code, expected.code) << render(*d);
  ASSERT_TRUE(d->data_file.has_value()) << render(*d);
  EXPECT_EQ(*d->data_file, path);
  EXPECT_EQ(d->row, expected.row) << render(*d);
  EXPECT_EQ(d->column, expected.column) << render(*d);
  const std::string text = d->message + "\n" + d->hint;
  EXPECT_NE(text.find(expected.phrase), std::string::npos) << render(*d);
  // The rendered form starts with the location, and shows no raw control bytes.
  const std::string shown = render(*d);
  EXPECT_EQ(shown.rfind(path + ":" + std::to_string(expected.row) + ":" + std::to_string(expected.column) + ": error: ", 0),
            0u)
      << shown;
  for (char c : shown) EXPECT_TRUE(c == '\n' || (static_cast<unsigned char>(c) >= 0x20 && c != 0x7f)) << shown;
}

INSTANTIATE_TEST_SUITE_P(Catalogue, BadRecordTest, ::testing::ValuesIn(kCatalogue),
                         [](const ::testing::TestParamInfo<BadRecord>& param) {
                           std::string name = param.param.file;
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

// Every file in the folder is in the table above (and so in the README), and the other way round.
TEST(BadRecords, EveryFileIsCatalogued) {
  std::set<std::string> listed;
  for (const auto& entry : kCatalogue) listed.insert(entry.file);
  std::set<std::string> present;
  for (const auto& entry : std::filesystem::directory_iterator(kBad))
    if (entry.path().filename() != "README.md") present.insert(entry.path().filename().string());
  EXPECT_EQ(listed, present);
  EXPECT_GE(listed.size(), 15u);
}

TEST(BadRecords, DecimalCommaFileReadsWithTheOption) {
  CsvOptions options;
  options.decimal_comma = true;
  auto record = read_csv(kBad + "decimal_comma.csv", options);
  ASSERT_TRUE(std::holds_alternative<Record>(record)) << render(std::get<Diagnostic>(record));
  const Record& r = std::get<Record>(record);
  auto x = complete_column(r, "x");
  ASSERT_TRUE(std::holds_alternative<const Column*>(x));
  EXPECT_EQ(std::get<const Column*>(x)->to_vector(), (std::vector<double>{0.0, 7.51, 14.92}));
  auto step = uniform_step(r, "t");
  ASSERT_TRUE(std::holds_alternative<double>(step));
  EXPECT_NEAR(std::get<double>(step), 0.01, 1e-15);
}

TEST(BadRecords, NonUniformFileCanBeResampled) {
  auto record = read_csv(kBad + "nonuniform_step.csv");
  ASSERT_TRUE(std::holds_alternative<Record>(record));
  auto resampled = resample_linear(std::get<Record>(record), "t", 0.01);
  ASSERT_TRUE(std::holds_alternative<Record>(resampled)) << render(std::get<Diagnostic>(resampled));
  const Record& r = std::get<Record>(resampled);
  EXPECT_EQ(r.rows(), 7u);
  auto step = uniform_step(r, "t");
  ASSERT_TRUE(std::holds_alternative<double>(step));
  EXPECT_NEAR(std::get<double>(step), 0.01, 1e-12);
  // The missing sample at t = 0.03 is the mean of its neighbours at 0.02 and 0.04.
  EXPECT_NEAR((*r.column("y"))[3], (0.02 + 0.12) / 2, 1e-15);
}

TEST(BadRecords, MissingFileAndDirectory) {
  auto missing = read_csv(kBad + "does_not_exist.csv");
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(missing));
  const Diagnostic& m = std::get<Diagnostic>(missing);
  EXPECT_EQ(m.code, "data-cannot-open");
  EXPECT_NE(m.message.find("does_not_exist.csv"), std::string::npos);
  EXPECT_NE(m.message.find("no such file"), std::string::npos);
  auto directory = read_csv(kBad);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(directory));
  EXPECT_EQ(std::get<Diagnostic>(directory).code, "data-is-directory");
}


// Special files are refused at once, before a byte is read: a FIFO with no writer does not block,
// /dev/zero is not read until memory runs out.
TEST(BadRecords, AFifoOrADeviceIsRefusedAtOnce) {
  const auto fifo = std::filesystem::temp_directory_path() / ("sidc-record-fifo-" + std::to_string(::getpid()));
  std::filesystem::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  auto from_fifo = read_csv(fifo.string());
  std::filesystem::remove(fifo);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(from_fifo));
  EXPECT_EQ(std::get<Diagnostic>(from_fifo).code, "data-not-a-regular-file");
  EXPECT_NE(std::get<Diagnostic>(from_fifo).message.find("is a FIFO, not a regular file"), std::string::npos) << std::get<Diagnostic>(from_fifo).message;
  auto from_zero = read_csv("/dev/zero");
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(from_zero));
  EXPECT_EQ(std::get<Diagnostic>(from_zero).message, "data file `/dev/zero` is a character device, not a regular file");
}

// A record truncated (or grown) between its fstat and its read is an error, never SIGBUS and never
// a silently shorter record: read_open_file told the size fstat gave before the truncation.
TEST(BadRecords, AFileShorterOrLongerThanItsSizeIsChanged) {
  const auto path = std::filesystem::temp_directory_path() / ("sidc-record-shrunk-" + std::to_string(::getpid()) + ".csv");
  { std::ofstream(path) << "t,y\n0,1\n0.1,2\n"; }
  const int fd = ::open(path.c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  const std::size_t size = std::filesystem::file_size(path);
  auto shrunk = read_open_file(fd, size + 100);  // as if the file had lost 100 bytes since its fstat
  ASSERT_TRUE(std::holds_alternative<FileRefusal>(shrunk));
  EXPECT_EQ(std::get<FileRefusal>(shrunk).kind, FileRefusal::Kind::changed);
  EXPECT_NE(std::get<FileRefusal>(shrunk).reason.find(std::to_string(size + 100) + " bytes long when opened, " + std::to_string(size)), std::string::npos)
      << std::get<FileRefusal>(shrunk).reason;
  ASSERT_EQ(::lseek(fd, 0, SEEK_SET), 0);
  auto grown = read_open_file(fd, size - 4);
  ASSERT_TRUE(std::holds_alternative<FileRefusal>(grown));
  EXPECT_EQ(std::get<FileRefusal>(grown).kind, FileRefusal::Kind::changed);
  ASSERT_EQ(::lseek(fd, 0, SEEK_SET), 0);
  auto whole = read_open_file(fd, size);
  ASSERT_TRUE(std::holds_alternative<FileBytes>(whole));
  EXPECT_EQ(std::string_view(std::get<FileBytes>(whole).data.get(), std::get<FileBytes>(whole).size), "t,y\n0,1\n0.1,2\n");
  ::close(fd);
  std::filesystem::remove(path);
}

// A file truncated over and over while it is read: each read gives a record or an error, and the
// process survives (with the mapping it used to, 4 tries in 12 ended in SIGBUS).
TEST(BadRecords, AFileTruncatedWhileReadGivesARecordOrAnError) {
  const auto path = std::filesystem::temp_directory_path() / ("sidc-record-truncated-" + std::to_string(::getpid()) + ".csv");
  std::string text = "t,y\n";
  for (int i = 0; i < 200000; ++i) text += std::to_string(i) + "," + std::to_string(i % 7) + "\n";
  std::atomic<bool> done{false};
  { std::ofstream(path, std::ios::binary) << text; }
  std::thread truncator([&] {
    while (!done) {
      std::filesystem::resize_file(path, text.size() / 3);
      std::ofstream(path, std::ios::binary) << text;
    }
  });
  int records = 0, errors = 0;
  for (int i = 0; i < 20; ++i) {
    auto read = read_csv(path.string());
    if (std::holds_alternative<Record>(read)) ++records;
    else ++errors;
  }
  done = true;
  truncator.join();
  std::filesystem::remove(path);
  EXPECT_EQ(records + errors, 20);
}

// The duplicate-name check is a hash lookup per name: a header of 300,000 columns is read at once
// (compared pair by pair it took over 20 s), and a duplicate at its far end is still found.
TEST(BadRecords, AWideHeaderIsCheckedForDuplicates) {
  const int n = 300000;
  std::string header, row;
  for (int k = 0; k < n; ++k) {
    header += (k ? "," : "") + fmt::format("c{}", k);
    row += k ? ",1" : "0";
  }
  auto wide = parse_csv(header + "\n" + row + "\n", "wide.csv");
  ASSERT_TRUE(std::holds_alternative<Record>(wide)) << render(std::get<Diagnostic>(wide));
  EXPECT_EQ(std::get<Record>(wide).names.size(), static_cast<std::size_t>(n));
  auto duplicated = parse_csv(header + ",c17\n" + row + ",1\n", "wide.csv");
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(duplicated));
  EXPECT_NE(std::get<Diagnostic>(duplicated).message.find("duplicate column name `c17` (first used in column 18)"), std::string::npos)
      << std::get<Diagnostic>(duplicated).message;
  EXPECT_EQ(std::get<Diagnostic>(duplicated).column, n + 1);
}

// A resampling step that would make more rows than the limit is an error before any allocation,
// and a step of 1e-300 (a row count past every integer type) is the same error.
TEST(BadRecords, AResamplingStepTooSmallIsAnError) {
  auto record = read_csv(kBad + "nonuniform_step.csv");
  ASSERT_TRUE(std::holds_alternative<Record>(record));
  for (double step : {1e-9, 1e-300}) {
    auto resampled = resample_linear(std::get<Record>(record), "t", step);
    ASSERT_TRUE(std::holds_alternative<Diagnostic>(resampled)) << step;
    const Diagnostic& d = std::get<Diagnostic>(resampled);
    EXPECT_EQ(d.code, "data-too-many-resampled-rows");
    EXPECT_NE(d.message.find("at most 1000000 are allowed"), std::string::npos) << d.message;
  }
  EXPECT_EQ(max_resampled_rows(10), 1000000u);
  EXPECT_EQ(max_resampled_rows(10000000), 160000000u);
  EXPECT_TRUE(resample_linear(std::vector<double>{0, 1, 2}, {{1, 2, 3}}, 1e-300).time.empty());
}

}  // namespace
}  // namespace sidc
