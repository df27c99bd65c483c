// The catalogue of flawed records in tests/data/bad (see its README.md): each file is read the way
// the runtime reads a record for a model with time `t`, output `y` and input `x` (read_csv, then
// complete_column for t, y, x, then uniform_step on t), and the first diagnostic must have the
// expected code, file, row, column and key phrase.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>

#include "runtime/records/records.hpp"
#include "runtime/records/sampling.hpp"

namespace sidc {
namespace {

const std::string kBad = std::string(SIDC_SOURCE_DIR) + "/tests/data/bad/";

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
  ASSERT_TRUE(std::holds_alternative<const std::vector<double>*>(x));
  EXPECT_EQ(*std::get<const std::vector<double>*>(x), (std::vector<double>{0.0, 7.51, 14.92}));
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

}  // namespace
}  // namespace sidc
