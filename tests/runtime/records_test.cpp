// Structural tests of the CSV reader: every accepted format quirk, the row -> line map, and the
// deferred cell faults. The flawed-file catalogue is in bad_records_test.cpp.
#include <gtest/gtest.h>

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>

#include "runtime/records/records.hpp"
#include "runtime/records/sampling.hpp"

namespace sidc {
namespace {

const std::string kData = std::string(SIDC_SOURCE_DIR "/tests/runtime/data/");

Record parsed(std::string_view text, const CsvOptions& options = {}) {
  auto result = parse_csv(text, "mem.csv", options);
  if (auto* d = std::get_if<Diagnostic>(&result)) {
    ADD_FAILURE() << "unexpected diagnostic: " << render(*d);
    return {};
  }
  return std::get<Record>(std::move(result));
}

Diagnostic failed(std::string_view text, const CsvOptions& options = {}) {
  auto result = parse_csv(text, "mem.csv", options);
  if (!std::holds_alternative<Diagnostic>(result)) {
    ADD_FAILURE() << "expected a diagnostic";
    return {};
  }
  return std::get<Diagnostic>(std::move(result));
}

Diagnostic column_error(const Record& r, std::string_view name) {
  auto result = complete_column(r, name);
  if (!std::holds_alternative<Diagnostic>(result)) {
    ADD_FAILURE() << "expected column `" << name << "` to be refused";
    return {};
  }
  return std::get<Diagnostic>(std::move(result));
}

std::vector<double> column_values(const Record& r, std::string_view name) {
  auto result = complete_column(r, name);
  if (auto* d = std::get_if<Diagnostic>(&result)) {
    ADD_FAILURE() << render(*d);
    return {};
  }
  return std::get<const Column*>(result)->to_vector();
}

TEST(Records, CommaHeaderAndRows) {
  const Record r = parsed("t,y,x\n0,1.5,-2\n0.01,2.5,3\n");
  ASSERT_EQ(r.names, (std::vector<std::string>{"t", "y", "x"}));
  ASSERT_EQ(r.rows(), 2u);
  EXPECT_EQ(column_values(r, "y"), (std::vector<double>{1.5, 2.5}));
  EXPECT_EQ(column_values(r, "x"), (std::vector<double>{-2, 3}));
  EXPECT_EQ(r.header_line, 1);
  EXPECT_EQ(r.line_of_row(0), 2);
  EXPECT_EQ(r.line_of_row(1), 3);
}

TEST(Records, FortranishNumbers) {
  const Record r = parsed("a\n1.5E+03\n.11019\n760.\n-.5\n+2\n1.5D+03\n2.5d-1\n1e-400\n  7  \n\"8.5\"\n");
  EXPECT_EQ(column_values(r, "a"), (std::vector<double>{1500, 0.11019, 760, -0.5, 2, 1500, 0.25, 0, 7, 8.5}));
}

// The reader's own fast path for short decimals must give, bit for bit, what std::from_chars
// gives; numbers are printed in many shapes so that both the fast path and the fallback run.
TEST(Records, NumbersReadExactlyAsFromChars) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> mantissa(-10, 10);
  std::uniform_int_distribution<int> exponent(-40, 40);
  const char* formats[] = {"%.17g", "%.6g", "%.9f", "%.3e", "%.15E", "%.1f", "%.0f", "%.12g", "%.20f"};
  std::string text = "v\n";
  std::vector<std::string> cells;
  for (int i = 0; i < 20000; ++i) {
    const double x = mantissa(rng) * std::pow(10.0, exponent(rng));
    char buffer[512];
    std::snprintf(buffer, sizeof buffer, formats[static_cast<std::size_t>(i) % std::size(formats)], x);
    cells.emplace_back(buffer);
    text += cells.back() + "\n";
  }
  for (const char* edge : {"0", "-0", "0.", ".0", "9007199254740993", "9007199254740992", "1e22", "1e23",
                           "1e-22", "1e-23", "123456789012345678", "1234567890123456789", "12345678901234567890",
                           "0.30000000000000004", "4.9e-324", "2.2250738585072014e-308", "1.7976931348623157e308",
                           "-12.5E+3", "7E-0", "0.000000000000000000000000123"}) {
    cells.emplace_back(edge);
    text += std::string(edge) + "\n";
  }
  const Record r = parsed(text);
  ASSERT_EQ(r.rows(), cells.size());
  const auto& values = *r.column("v");
  for (std::size_t i = 0; i < cells.size(); ++i) {
    double expected = 0;
    const auto [ptr, ec] = std::from_chars(cells[i].data(), cells[i].data() + cells[i].size(), expected);
    ASSERT_EQ(ec, std::errc()) << cells[i];
    ASSERT_EQ(std::bit_cast<std::uint64_t>(values[i]), std::bit_cast<std::uint64_t>(expected)) << cells[i];
  }
}

TEST(Records, SeparatorDetection) {
  EXPECT_EQ(column_values(parsed("t;y\n1;2\n3;4\n"), "y"), (std::vector<double>{2, 4}));
  EXPECT_EQ(column_values(parsed("t y\n1 2\n3\t \t4\n"), "y"), (std::vector<double>{2, 4}));
  EXPECT_EQ(column_values(parsed("  t\ty  \n  1\t2\n"), "y"), (std::vector<double>{2}));
  EXPECT_EQ(column_values(parsed("t , y\n1 , 2\n"), "y"), (std::vector<double>{2}));
}

TEST(Records, StrictTabSeparatorAllowsEmptyCells) {
  CsvOptions options;
  options.separator = '\t';
  const Record r = parsed("t\ty\tx\n0\t\t5\n1\t2\t6\n", options);
  ASSERT_EQ(r.rows(), 2u);
  EXPECT_EQ(column_values(r, "x"), (std::vector<double>{5, 6}));
  EXPECT_EQ(column_error(r, "y").code, "data-empty-cell");
}

TEST(Records, LineEndsCommentsBlankLinesAndBom) {
  const std::string text = "\xEF\xBB\xBF# a comment\r\n\r\nt,y\r\n0,1\r\n   # indented comment\r\n\r\n1,2\r\n";
  const Record r = parsed(text);
  EXPECT_EQ(r.names, (std::vector<std::string>{"t", "y"}));
  EXPECT_EQ(column_values(r, "y"), (std::vector<double>{1, 2}));
  EXPECT_EQ(r.header_line, 3);
  EXPECT_EQ(r.line_of_row(0), 4);
  EXPECT_EQ(r.line_of_row(1), 7);
  // Old Mac line ends (CR only) and a last line without a line end.
  const Record mac = parsed("t,y\r0,1\r1,2");
  EXPECT_EQ(column_values(mac, "y"), (std::vector<double>{1, 2}));
  EXPECT_EQ(mac.line_of_row(1), 3);
}

TEST(Records, QuotedHeaderWithSeparatorAndEscapedQuote) {
  const Record r = parsed("\"time, s\",\"say \"\"hi\"\"\", plain \n1,2,3\n");
  EXPECT_EQ(r.names, (std::vector<std::string>{"time, s", "say \"hi\"", "plain"}));
}

TEST(Records, TrailingSeparatorOnEveryLine) {
  const Record r = parsed("\"V1\",\"V2\",\n0.0057756,0.0093978,\n0.0066102,0.012971,\n\n");
  EXPECT_EQ(r.names, (std::vector<std::string>{"V1", "V2"}));
  EXPECT_EQ(column_values(r, "V2"), (std::vector<double>{0.0093978, 0.012971}));
  // Rows may end with or without the trailing separator, whatever the header does.
  const Record mixed = parsed("a,b\n1,2,\n3,4\n");
  EXPECT_EQ(column_values(mixed, "b"), (std::vector<double>{2, 4}));
}

TEST(Records, SilverboxExcerpt) {
  auto result = read_csv(kData + "silverbox_SNLS80mV_head.csv");
  ASSERT_TRUE(std::holds_alternative<Record>(result)) << render(std::get<Diagnostic>(result));
  const Record& r = std::get<Record>(result);
  EXPECT_EQ(r.names, (std::vector<std::string>{"V1", "V2"}));
  ASSERT_EQ(r.rows(), 20u);
  EXPECT_EQ(column_values(r, "V1")[0], 0.0057756);
  EXPECT_EQ(column_values(r, "V2")[1], 0.012971);
}

TEST(Records, SchroederOverloadColumnsEmptyAfterFirstRow) {
  auto result = read_csv(kData + "silverbox_Schroeder80mV_head.csv");
  ASSERT_TRUE(std::holds_alternative<Record>(result)) << render(std::get<Diagnostic>(result));
  const Record& r = std::get<Record>(result);
  EXPECT_EQ(r.names, (std::vector<std::string>{"Ovld2", "Ovld1", "V1", "V2"}));
  ASSERT_EQ(r.rows(), 20u);
  EXPECT_EQ(column_values(r, "V1")[1], 0.0060811);
  EXPECT_EQ((*r.column("Ovld2"))[0], 0.0);
  const Diagnostic d = column_error(r, "Ovld1");
  EXPECT_EQ(d.code, "data-empty-cell");
  EXPECT_EQ(d.row, 3);     // line 3 = second data row
  EXPECT_EQ(d.column, 2);  // Ovld1 is the second field
}

TEST(Records, CascadedTanksTsOnlyInFirstRow) {
  auto result = read_csv(kData + "cascaded_tanks_head.csv");
  ASSERT_TRUE(std::holds_alternative<Record>(result)) << render(std::get<Diagnostic>(result));
  const Record& r = std::get<Record>(result);
  EXPECT_EQ(r.names, (std::vector<std::string>{"uEst", "uVal", "yEst", "yVal", "Ts"}));
  EXPECT_EQ(r.rows(), 20u);
  EXPECT_EQ(column_values(r, "yEst")[0], 5.205);
  EXPECT_EQ((*r.column("Ts"))[0], 4.0);
  EXPECT_EQ(cell_fault((*r.column("Ts"))[1]), CellFault::empty);
  const Diagnostic d = column_error(r, "Ts");
  EXPECT_EQ(d.code, "data-empty-cell");
  EXPECT_EQ(*d.data_file, kData + "cascaded_tanks_head.csv");
  EXPECT_EQ(d.row, 3);
  EXPECT_EQ(d.column, 5);
  EXPECT_NE(d.message.find("`Ts`"), std::string::npos);
}

TEST(Records, NoHeaderNamesColumnsC1C2) {
  const Record r = parsed("0 1.5\n0.01 2.5\n");
  EXPECT_EQ(r.names, (std::vector<std::string>{"c1", "c2"}));
  EXPECT_EQ(r.header_line, 0);
  EXPECT_EQ(column_values(r, "c2"), (std::vector<double>{1.5, 2.5}));
  EXPECT_EQ(r.line_of_row(0), 1);
  // Forcing a header reads a numeric first line as names.
  CsvOptions present;
  present.header = CsvOptions::Header::present;
  EXPECT_EQ(parsed("1,2\n3,4\n", present).names, (std::vector<std::string>{"1", "2"}));
  CsvOptions absent;
  absent.header = CsvOptions::Header::absent;
  const Record forced = parsed("1,2\n3,4\n", absent);
  EXPECT_EQ(forced.rows(), 2u);
  // An empty header name (a pandas index column) becomes c<field>.
  EXPECT_EQ(parsed(",y\n0,1\n").names, (std::vector<std::string>{"c1", "y"}));
}

TEST(Records, EmptyRowsFromSpreadsheetsAreSkipped) {
  const Record r = parsed("t,y,\n0,1,\n,,\n1,2,\n,\n , \n");
  EXPECT_EQ(r.rows(), 2u);
  EXPECT_EQ(column_values(r, "t"), (std::vector<double>{0, 1}));
  EXPECT_EQ(r.line_of_row(1), 4);
}

TEST(Records, CellFaultsAreDeferredUntilTheColumnIsUsed) {
  const Record r = parsed("t,y,note,z\n0,1,hello,nan\n1,2,,inf\n2,3,x,1e999\n");
  ASSERT_EQ(r.rows(), 3u);
  EXPECT_EQ(column_values(r, "t"), (std::vector<double>{0, 1, 2}));
  EXPECT_EQ(cell_fault((*r.column("note"))[0]), CellFault::non_numeric);
  EXPECT_EQ(cell_fault((*r.column("note"))[1]), CellFault::empty);
  EXPECT_EQ(cell_fault((*r.column("z"))[0]), CellFault::not_a_number);
  EXPECT_EQ(cell_fault((*r.column("z"))[1]), CellFault::infinite);
  EXPECT_EQ(cell_fault((*r.column("z"))[2]), CellFault::out_of_range);
  const Diagnostic note = column_error(r, "note");
  EXPECT_EQ(note.code, "data-non-numeric-cell");
  EXPECT_NE(note.message.find("`hello`"), std::string::npos);
  EXPECT_EQ(note.row, 2);
  EXPECT_EQ(note.column, 3);
  EXPECT_EQ(column_error(r, "z").code, "data-nan-cell");
}

TEST(Records, DecimalCommaOption) {
  const std::string text = "t;y\n0,5;1,25\n1,5;-2,5e1\n";
  const Record plain = parsed(text);
  const Diagnostic d = column_error(plain, "y");
  EXPECT_EQ(d.code, "data-decimal-comma");
  EXPECT_NE(d.hint.find("decimal-comma option"), std::string::npos);
  CsvOptions options;
  options.decimal_comma = true;
  EXPECT_EQ(column_values(parsed(text, options), "y"), (std::vector<double>{1.25, -25}));
  EXPECT_EQ(column_values(parsed(text, options), "t"), (std::vector<double>{0.5, 1.5}));
  options.separator = ',';
  EXPECT_FALSE(options.is_valid());
  EXPECT_EQ(failed(text, options).code, "data-invalid-options");
}

TEST(Records, UnknownColumnSuggestsNearestName) {
  const Record r = parsed("time,yEst,uEst\n0,1,2\n");
  const Diagnostic d = column_error(r, "yest");
  EXPECT_EQ(d.code, "data-unknown-column");
  EXPECT_EQ(d.hint, "did you mean `yEst`?");
  EXPECT_EQ(d.row, 1);
  // One-letter names: only a difference of case counts as a slip.
  const Record single = parsed("t,y,u\n0,1,2\n");
  EXPECT_EQ(column_error(single, "x").hint.find("did you mean"), std::string::npos);
  EXPECT_EQ(column_error(single, "Y").hint, "did you mean `y`?");
}

TEST(Records, RaggedRowsAreFileErrors) {
  Diagnostic d = failed("a,b,c\n1,2,3\n4,5\n");
  EXPECT_EQ(d.code, "data-too-few-fields");
  EXPECT_EQ(d.row, 3);
  EXPECT_EQ(d.column, 3);
  d = failed("a,b\n1,2\n4,5,6\n");
  EXPECT_EQ(d.code, "data-too-many-fields");
  EXPECT_EQ(d.row, 3);
  EXPECT_EQ(d.column, 3);
  d = failed("a,b\n1,2\n4,5,,\n");  // two trailing separators: one field too many
  EXPECT_EQ(d.code, "data-too-many-fields");
  d = failed("a b\n1 2 3\n");
  EXPECT_EQ(d.code, "data-too-many-fields");
  EXPECT_EQ(d.column, 3);
}

TEST(Records, SelectedRowsKeepTheirLines) {
  std::string text = "# header comment\nt,y\n";
  for (int i = 0; i < 40; ++i) {
    if (i == 10) text += "# a comment in the middle\n";
    text += std::to_string(i) + "," + (i == 31 ? std::string("oops") : std::to_string(i * i)) + "\n";
  }
  const Record r = parsed(text);
  ASSERT_EQ(r.rows(), 40u);
  EXPECT_EQ(r.line_of_row(9), 12);
  EXPECT_EQ(r.line_of_row(10), 14);  // after the comment line
  const Diagnostic whole = column_error(r, "y");
  EXPECT_EQ(whole.row, 2 + 1 + 31 + 1);  // comment, header, 31 rows, the middle comment
  // Rows 20, 22, ..., 38: row 31 is not among them, so the column is complete.
  const Record even = select_rows(r, {20, 40}, 2);
  EXPECT_EQ(even.rows(), 10u);
  EXPECT_EQ(column_values(even, "t").front(), 20);
  EXPECT_EQ(even.line_of_row(1), r.line_of_row(22));
  // Rows 21, 23, ...: row 31 is among them and the diagnostic still names its line and text.
  const Record odd = select_rows(r, {21, 40}, 2);
  const Diagnostic d = column_error(odd, "y");
  EXPECT_EQ(d.row, whole.row);
  EXPECT_NE(d.message.find("`oops`"), std::string::npos);
}

TEST(Records, FileErrors) {
  auto missing = read_csv(kData + "no_such_file.csv");
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(missing));
  EXPECT_EQ(std::get<Diagnostic>(missing).code, "data-cannot-open");
  auto directory = read_csv(kData);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(directory));
  EXPECT_EQ(std::get<Diagnostic>(directory).code, "data-is-directory");
  EXPECT_EQ(failed("").code, "data-empty-file");
  EXPECT_EQ(failed("\n\n  \n").code, "data-empty-file");
  EXPECT_EQ(failed("a,b\n").code, "data-no-rows");
  EXPECT_EQ(failed("a,b\n,,\n").code, "data-no-rows");
}

// Random bytes drawn from the characters that matter to the reader: no crash, no hang, and a
// record that comes back is consistent.
TEST(Records, RandomInputNeverCrashes) {
  const std::string alphabet = "0123456789.,;\t \n\r\"#eE+-dDnaif\x01\xff";
  std::mt19937 rng(20240611);
  for (int trial = 0; trial < 3000; ++trial) {
    std::string text(rng() % 80, ' ');
    for (char& c : text) c = alphabet[rng() % alphabet.size()];
    auto result = parse_csv(text, "fuzz.csv");
    if (auto* r = std::get_if<Record>(&result)) {
      ASSERT_GT(r->rows(), 0u);
      ASSERT_EQ(r->columns.size(), r->names.size());
      for (const auto& column : r->columns) ASSERT_EQ(column.size(), r->rows());
      for (std::size_t row = 0; row < r->rows(); ++row) ASSERT_GT(r->line_of_row(row), 0);
    } else {
      const Diagnostic& d = std::get<Diagnostic>(result);
      ASSERT_FALSE(d.code.empty());
      ASSERT_FALSE(render(d).empty());
    }
  }
}

TEST(Records, LongLineIsRefusedWithoutFloodingTheMessage) {
  std::string text = "a,b\n1," + std::string(1 << 20, 'z') + "\n";
  const Record r = parsed(text);
  const Diagnostic d = column_error(r, "b");
  EXPECT_EQ(d.code, "data-non-numeric-cell");
  EXPECT_LT(render(d).size(), 600u);
}

}  // namespace
}  // namespace sidc

namespace sidc {
namespace {

// Rows' text of a few hundred kB with comments, blank lines, CRLF and faulty cells in both halves.
std::string mixed_rows(std::size_t rows) {
  std::string text = "# a comment before the header\nt,x,y\n";
  std::mt19937 random(7);
  for (std::size_t k = 0; k < rows; ++k) {
    if (k % 997 == 13) text += "# a comment line\n";
    if (k % 1231 == 5) text += "\n";
    std::string y = std::to_string(std::uniform_real_distribution<double>(-1, 1)(random));
    if (k == 100 || k == rows - 100) y = "n/a";  // a fault in each half
    if (k == rows / 2 + 7) y = "";
    text += std::to_string(0.001 * static_cast<double>(k)) + "," + std::to_string(k) + "," + y + (k % 3 == 0 ? "\r\n" : "\n");
  }
  return text;
}

TEST(Records, TwoThreadsGiveTheSameRecordAsOne) {
  const std::string text = mixed_rows(20000);
  CsvOptions one, two;
  one.parallel_above_bytes = SIZE_MAX;
  two.parallel_above_bytes = 1;
  const Record a = parsed(text, one), b = parsed(text, two);
  ASSERT_EQ(a.rows(), 20000u);
  ASSERT_EQ(a.names, b.names);
  ASSERT_EQ(a.rows(), b.rows());
  for (std::size_t j = 0; j < a.columns.size(); ++j) {
    for (std::size_t i = 0; i < a.rows(); ++i)
      ASSERT_EQ(std::bit_cast<std::uint64_t>(a.columns[j][i]), std::bit_cast<std::uint64_t>(b.columns[j][i])) << j << " " << i;
    ASSERT_EQ(a.first_faults[j].size(), b.first_faults[j].size());
    for (std::size_t k = 0; k < a.first_faults[j].size(); ++k) {
      EXPECT_EQ(a.first_faults[j][k].row, b.first_faults[j][k].row);
      EXPECT_EQ(a.first_faults[j][k].text, b.first_faults[j][k].text);
    }
  }
  EXPECT_EQ(a.first_faults[2].size(), 3u);
  for (std::size_t i = 0; i < a.rows(); ++i) ASSERT_EQ(a.line_of_row(i), b.line_of_row(i)) << i;
  EXPECT_EQ(a.line_jumps, b.line_jumps);
}

TEST(Records, TwoThreadsReportTheSameLineForARaggedRow) {
  CsvOptions one, two;
  one.parallel_above_bytes = SIZE_MAX;
  two.parallel_above_bytes = 1;
  std::string text = mixed_rows(5000);
  const std::size_t late = text.find('\n', text.size() * 3 / 4);
  text.insert(late, ",9");  // a row with a fourth field, in the second half
  const std::string expected = render(failed(text, one));
  EXPECT_NE(expected.find("field"), std::string::npos) << expected;
  EXPECT_EQ(render(failed(text, two)), expected);
  const std::size_t early = text.find('\n', text.size() / 4);
  text.insert(early, ",9");  // and one in the first half: that one is reported
  const std::string first = render(failed(text, one));
  EXPECT_NE(first, expected);
  EXPECT_EQ(render(failed(text, two)), first);
}

}  // namespace
}  // namespace sidc
