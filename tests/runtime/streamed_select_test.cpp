// `sidc select`'s rows streamed (runtime/select/streamed_rows.hpp) against the whole rows: the same
// subsets, G, drift shares and choice to rounding, on the thesis' section 4-1 models (guards, the
// integrated form), several records, a group of two equations, row weights from an expression;
// a record that turns bad gives the whole rows' diagnostic. And LineShareSums, the drift test
// over pieces, against operation_line_share.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include "compiler/pipeline.hpp"
#include "runtime/records/bind_record.hpp"
#include "runtime/records/records.hpp"
#include "runtime/select/select.hpp"
#include "runtime/select/size_rule.hpp"

#include "support/shell.hpp"
#include "support/synthetic_record.hpp"
#include "support/thesis_record.hpp"

namespace sidc {
namespace {

using testing::appendix_a;
using testing::compiled_text;

SelectOptions whole_rows(SelectOptions o = {}) {
  o.fit.stream_above_entries = std::numeric_limits<std::size_t>::max();
  return o;
}

// Every record streamed, in blocks of a few rows, integrals carried over short stretches, on two threads.
SelectOptions streamed(SelectOptions o = {}, std::size_t block_rows = 7) {
  o.fit.stream_above_entries = 0;
  o.fit.stream_block_rows = block_rows;
  o.fit.stream_threads = 2;
  o.fit.stream_stretch_rows = 3 * block_rows + 2;
  return o;
}

SelectSummary selected(const ir::Model& m, const std::vector<SampledRecord>& records, const SelectOptions& o) {
  auto result = select_operations(m, records, o);
  EXPECT_TRUE(std::holds_alternative<SelectSummary>(result)) << render(std::get<Diagnostic>(result));
  return std::holds_alternative<SelectSummary>(result) ? std::get<SelectSummary>(result) : SelectSummary{};
}

void expect_same_selection(const SelectSummary& whole, const SelectSummary& stream) {
  ASSERT_TRUE(whole.ok()) << whole.message;
  ASSERT_TRUE(stream.ok()) << stream.message;
  ASSERT_EQ(whole.groups.size(), stream.groups.size());
  for (std::size_t gi = 0; gi < whole.groups.size(); ++gi) {
    SCOPED_TRACE(::testing::Message() << "group " << gi);
    const GroupSelection& a = whole.groups[gi];
    const GroupSelection& b = stream.groups[gi];
    EXPECT_EQ(a.n, b.n);
    EXPECT_EQ(a.blocks, b.blocks);
    EXPECT_EQ(a.columns, b.columns);
    ASSERT_EQ(a.drift.size(), b.drift.size());
    for (std::size_t k = 0; k < a.drift.size(); ++k) {
      EXPECT_EQ(a.drift[k].column, b.drift[k].column);
      EXPECT_EQ(a.drift[k].set_aside, b.drift[k].set_aside);
      EXPECT_NEAR(a.drift[k].share, b.drift[k].share, 1e-10);
    }
    ASSERT_EQ(a.rows.size(), b.rows.size());
    for (std::size_t k = 0; k < a.rows.size(); ++k) {
      EXPECT_EQ(a.rows[k].parameters, b.rows[k].parameters) << "size " << a.rows[k].size;
      EXPECT_NEAR(a.rows[k].G, b.rows[k].G, 1e-8 * a.rows[k].G + 1e-300) << "size " << a.rows[k].size;
      if (std::isfinite(a.rows[k].cv)) {
        EXPECT_NEAR(a.rows[k].cv, b.rows[k].cv, 1e-7 * a.rows[k].cv) << "size " << a.rows[k].size;
      }
    }
    EXPECT_EQ(a.chosen, b.chosen);
    EXPECT_EQ(a.non_contributory, b.non_contributory);
  }
}

TEST(StreamedSelect, ThesisModelsGiveTheWholeRowsSelection) {
  for (const char* name : {"derivative_form.sid", "quasi_linear.sid"}) {
    SCOPED_TRACE(name);
    const std::string path = std::string(SIDC_SOURCE_DIR "/examples/thesis-4-1/") + name;
    const ir::Model m = compiled_text(path, testing::read_text(path));
    const std::vector<SampledRecord> records{appendix_a(m), appendix_a(m, 2)};
    SelectOptions o;
    o.fit.to = 0.82;
    const SelectSummary whole = selected(m, records, whole_rows(o));
    for (std::size_t block : {1, 7, 64}) {
      SCOPED_TRACE(block);
      expect_same_selection(whole, selected(m, records, streamed(o, block)));
    }
  }
}

// Two outputs sharing the parameter `a`: one group of two equations, rows interleaved by sample.
// y = sin t + ..., z follows it; x drives y. A weight expression and a drift absorber (int(cos(0.01*y))
// is nearly t) in the integrated equations.
TEST(StreamedSelect, TwoEquationsWeightsAndADriftAbsorber) {
  const ir::Model m = compiled_text("two.sid",
                                    "input x\noutput y, z\nparam a, b, c, d, e\nset integrate = 1\nset weights = 1 + 0.5*x^2\n"
                                    "a*y' + b*y + d*cos(0.01*y) = x\n"
                                    "a*z' + c*z + e*z^3 = y\n");
  const SampledRecord r = testing::synthetic_record(3000, 0.01, {
      {"x", [](double t) { return std::sin(0.7 * t) + 0.3 * std::cos(2.3 * t); }},
      {"y", [](double t) { return std::sin(0.5 * t + 0.2) + 0.01 * std::sin(17.0 * t); }},
      {"z", [](double t) { return std::cos(0.4 * t) + 0.02 * std::cos(11.0 * t); }}});
  const SelectSummary whole = selected(m, {r}, whole_rows());
  ASSERT_EQ(whole.groups.size(), 1u);
  ASSERT_EQ(whole.groups[0].equations.size(), 2u);
  EXPECT_FALSE(whole.groups[0].drift.empty());
  for (std::size_t block : {5, 100}) {
    SCOPED_TRACE(block);
    expect_same_selection(whole, selected(m, {r}, streamed({}, block)));
  }
}

TEST(StreamedSelect, ARecordThatTurnsBadGivesTheWholeRowsDiagnostic) {
  const std::string path = SIDC_SOURCE_DIR "/examples/thesis-4-1/quasi_linear.sid";
  const ir::Model m = compiled_text(path, testing::read_text(path));
  SampledRecord r = appendix_a(m);
  r.signals["y"].owned()[40] = std::log(-1.0);  // NaN in the middle of the window
  SelectOptions o;
  o.fit.to = 0.82;
  const auto whole = select_operations(m, {r}, whole_rows(o));
  const auto stream = select_operations(m, {r}, streamed(o));
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(whole));
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(stream));
  EXPECT_EQ(render(std::get<Diagnostic>(whole)), render(std::get<Diagnostic>(stream)));
}

TEST(LineShareSums, PiecesJoinedInOrderGiveTheWholeColumnsShares) {
  std::mt19937_64 random(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  const Eigen::Index n = 203;
  Eigen::MatrixXd values(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / 10;
    values(i, 0) = noise(random);                         // no line at all
    values(i, 1) = std::sin(t) + 0.1 * noise(random);     // partly
    values(i, 2) = 0.5 * t * t + 1e-3 * noise(random);    // a parabola: its differences are nearly a line
  }
  for (int integrations = 0; integrations <= 3; ++integrations) {
    SCOPED_TRACE(integrations);
    const std::vector<double> expected = operation_line_share(values, integrations);
    // Pieces of 1, 2, 3, ... rows (some shorter than I), each fed in chunks of at most 4 rows.
    LineShareSums total(static_cast<std::size_t>(n), 3, integrations);
    Eigen::Index start = 0;
    for (Eigen::Index size = 1; start < n; ++size) {
      const Eigen::Index end = std::min(n, start + size);
      LineShareSums piece(static_cast<std::size_t>(n), 3, integrations);
      for (Eigen::Index c = start; c < end; c += 4)
        piece.add(static_cast<std::size_t>(c), values.middleRows(c, std::min<Eigen::Index>(4, end - c)));
      total.join(piece);
      start = end;
    }
    const std::vector<double> got = total.shares();
    ASSERT_EQ(got.size(), expected.size());
    for (std::size_t c = 0; c < got.size(); ++c) EXPECT_NEAR(got[c], expected[c], 1e-12) << "column " << c;
    if (integrations == 1) {
      EXPECT_GT(got[2], 0.999);  // the parabola's first difference is a line
    }
  }
}

TEST(LineShareSums, AZeroColumnHasNoShare) {
  LineShareSums sums(10, 2, 1);
  Eigen::MatrixXd values = Eigen::MatrixXd::Zero(10, 2);
  for (Eigen::Index i = 0; i < 10; ++i) values(i, 1) = static_cast<double>(i * i);
  sums.add(0, values);
  const auto share = sums.shares();
  EXPECT_TRUE(std::isnan(share[0]));
  EXPECT_NEAR(share[1], operation_line_share(values, 1)[1], 1e-12);
}

}  // namespace
}  // namespace sidc
