// A record cut at its gaps (runtime/records/bind_record.hpp, unbroken_stretches; `--split-at-gaps`):
// missing samples, faulty cells in the columns the model reads, repeated and backward times end a
// stretch; a faulty cell in a column the model does not read does not; short stretches are set
// apart; a record without a time column is the binding's error.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "runtime/records/bind_record.hpp"
#include "support/simulation.hpp"

namespace sidc::gaps_test {

ir::Model model_of(const std::vector<std::pair<std::string, ir::Signal::Kind>>& signals) {
  ir::Model m;
  for (const auto& [name, kind] : signals) {
    ir::Signal s;
    s.name = name;
    s.kind = kind;
    m.signals.push_back(s);
  }
  return m;
}

const ir::Model kModel = model_of({{"x", ir::Signal::Kind::input}, {"y", ir::Signal::Kind::output}});

// Rows t = 0, 0.1, ... with x = 1 and y = t; row k written as `replaced` gives it (empty: no row).
std::string record_text(std::size_t rows, const std::vector<std::pair<std::size_t, std::string>>& replaced = {}, bool note = false) {
  std::string text = note ? "t,x,y,note\n" : "t,x,y\n";
  for (std::size_t k = 0; k < rows; ++k) {
    std::string row = std::to_string(0.1 * static_cast<double>(k)) + ",1," + std::to_string(0.1 * static_cast<double>(k)) + (note ? ",5" : "");
    for (const auto& [at, with] : replaced)
      if (at == k) row = with;
    if (!row.empty()) text += row + "\n";
  }
  return text;
}

Stretches stretches_of(const std::string& text, std::size_t min_rows = 3) {
  auto record = parse_csv(text, "gaps.csv");
  EXPECT_TRUE(std::holds_alternative<Record>(record));
  auto found = unbroken_stretches(std::get<Record>(record), ir::DataSource{}, kModel, BindOptions{}, min_rows);
  EXPECT_TRUE(std::holds_alternative<Stretches>(found)) << std::get<Diagnostic>(found).message;
  return std::get<Stretches>(found);
}

std::vector<std::pair<std::size_t, std::size_t>> ranges(const std::vector<IndexRange>& r) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (const auto& x : r) out.emplace_back(x.begin, x.end);
  return out;
}

using Ranges = std::vector<std::pair<std::size_t, std::size_t>>;

TEST(UnbrokenStretches, ARecordWithoutGapsIsOneStretch) {
  const Stretches s = stretches_of(record_text(50));
  EXPECT_EQ(ranges(s.kept), (Ranges{{0, 50}}));
  EXPECT_TRUE(s.short_ones.empty());
  EXPECT_EQ(s.rows_left_out, 0u);
}

TEST(UnbrokenStretches, MissingSamplesEndAStretch) {
  // Rows 20..24 never written: the record's row 20 is t = 2.5.
  const Stretches s = stretches_of(record_text(50, {{20, ""}, {21, ""}, {22, ""}, {23, ""}, {24, ""}}));
  EXPECT_EQ(ranges(s.kept), (Ranges{{0, 20}, {20, 45}}));
  EXPECT_EQ(s.rows_left_out, 0u);
}

TEST(UnbrokenStretches, AFaultyCellInAColumnReadLeavesItsRowOut) {
  const Stretches s = stretches_of(record_text(50, {{10, "1.0,1,"}, {30, "3.0,NaN,3.0"}}));
  EXPECT_EQ(ranges(s.kept), (Ranges{{0, 10}, {11, 30}, {31, 50}}));
  EXPECT_EQ(s.rows_left_out, 2u);
  // In a column the model does not read, it is no gap.
  EXPECT_EQ(ranges(stretches_of(record_text(50, {{10, "1.0,1,1.0,"}}, true)).kept), (Ranges{{0, 50}}));
}

TEST(UnbrokenStretches, RepeatedAndBackwardTimesEndAStretch) {
  const Stretches s = stretches_of(record_text(40, {{10, "0.9,1,0.9"}, {25, "2.3,1,2.3"}}));
  // Row 10 repeats t = 0.9 (spacing 0), row 25 steps back to 2.3: each starts a stretch, and the
  // row after each (spacings 0.2 and 0.3) starts another.
  EXPECT_EQ(ranges(s.kept), (Ranges{{0, 10}, {11, 25}, {26, 40}}));
  EXPECT_EQ(ranges(s.short_ones), (Ranges{{10, 11}, {25, 26}}));
}

TEST(UnbrokenStretches, ShortStretchesAreSetApart) {
  const Stretches s = stretches_of(record_text(40, {{5, "0.5,,0.5"}, {8, "0.8,,0.8"}}), 10);
  EXPECT_EQ(ranges(s.kept), (Ranges{{9, 40}}));
  EXPECT_EQ(ranges(s.short_ones), (Ranges{{0, 5}, {6, 8}}));
}

TEST(UnbrokenStretches, AClippedOutputsRailSamplesAreLeftOut) {
  // y = sin(t) read by a sensor that saturates at 0.8: every run at 0.8 cut out.
  std::string text = "t,x,y\n";
  std::size_t at_rail = 0;
  for (std::size_t k = 0; k < 400; ++k) {
    const double t = 0.05 * static_cast<double>(k), y = std::min(0.8, std::sin(t) + 0.001 * std::sin(37.0 * t));
    at_rail += y == 0.8;
    text += std::to_string(t) + ",1," + (y == 0.8 ? std::string("0.8") : std::to_string(y)) + "\n";
  }
  auto record = parse_csv(text, "clipped.csv");
  ASSERT_TRUE(std::holds_alternative<Record>(record));
  const ir::Model dynamic = testing::normalized("model clipped\ninput x\noutput y\nparam a, b\na*y' + b*y = x\n");
  auto found = unbroken_stretches(std::get<Record>(record), ir::DataSource{}, dynamic, BindOptions{}, 5);
  ASSERT_TRUE(std::holds_alternative<Stretches>(found));
  const Stretches& s = std::get<Stretches>(found);
  EXPECT_EQ(s.rows_clipped, at_rail);
  EXPECT_EQ(s.rows_left_out, at_rail);
  EXPECT_GE(s.kept.size(), 3u);
  // A static model's rows are no time series: nothing is taken for clipped.
  EXPECT_EQ(stretches_of(text, 5).rows_clipped, 0u);
}

TEST(UnbrokenStretches, WithoutATimeColumnOrAnyGoodPairItIsAnError) {
  auto record = parse_csv("x,y\n1,2\n3,4\n", "no_time.csv");
  auto found = unbroken_stretches(std::get<Record>(record), ir::DataSource{}, kModel, BindOptions{}, 3);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(found));
  EXPECT_EQ(std::get<Diagnostic>(found).code, "data-no-time-column");
  auto bad = parse_csv("t,x,y\n0,1,\n0.1,,2\n0.2,1,\n", "bad.csv");
  found = unbroken_stretches(std::get<Record>(bad), ir::DataSource{}, kModel, BindOptions{}, 3);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(found));
  EXPECT_EQ(std::get<Diagnostic>(found).code, "data-no-stretch");
  // A column the model reads and the record lacks is the binding's own error.
  auto missing = parse_csv("t,x\n0,1\n0.1,2\n", "missing.csv");
  found = unbroken_stretches(std::get<Record>(missing), ir::DataSource{}, kModel, BindOptions{}, 3);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(found));
  EXPECT_NE(std::get<Diagnostic>(found).message.find("`y`"), std::string::npos) << std::get<Diagnostic>(found).message;
}

}  // namespace sidc::gaps_test
