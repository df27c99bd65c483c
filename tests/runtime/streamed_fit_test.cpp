// The streamed fit (FitOptions::stream_above_entries, runtime/operators/block_evaluator.hpp,
// TriangularAccumulator::rows_area) against the dense one on problems where both run: the thesis'
// section 4-1 models (guards, an input defined in the model, the integrated form with its
// integration constants), several records, every other sample, row weights, and the section 4-2
// process model (two groups, initial values y2(0)). Blocks are made small (a few rows) so that
// every problem is cut into many blocks on two threads; the two paths must agree to rounding.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "compiler/pipeline.hpp"
#include "runtime/records/bind_record.hpp"
#include "runtime/operators/block_evaluator.hpp"
#include "runtime/solve/fit.hpp"

#include "support/shell.hpp"
#include "support/synthetic_record.hpp"
#include "support/thesis_record.hpp"

namespace sidc {
namespace {

using testing::appendix_a;
using testing::compiled_text;

// The file's text (tests/support/shell.hpp).
std::string read(const std::string& path) { return testing::read_text(path); }

ir::Model compiled_file(const std::string& path) { return compiled_text(path, read(path)); }

FitOptions thesis_options() {
  FitOptions o;
  o.to = 0.82;  // the models' `set to`
  return o;
}

FitOptions streamed(FitOptions o, std::size_t block_rows = 7, int threads = 2) {
  o.stream_above_entries = 0;
  o.stream_block_rows = block_rows;
  o.stream_threads = threads;
  o.stream_stretch_rows = 3 * block_rows + 1;  // integrals carried over many stretches, each a few blocks, not whole
  return o;
}

FitSummary fitted(const ir::Model& m, const std::vector<SampledRecord>& records, const FitOptions& o) {
  auto result = fit(m, records, o);
  EXPECT_TRUE(std::holds_alternative<FitSummary>(result)) << render(std::get<Diagnostic>(result));
  return std::holds_alternative<FitSummary>(result) ? std::get<FitSummary>(result) : FitSummary{};
}

// Estimates, G(a), standard errors, n, rank, regions, records: the same to rounding.
void expect_same_fit(const FitSummary& dense, const FitSummary& stream) {
  ASSERT_EQ(dense.groups.size(), stream.groups.size());
  for (std::size_t gi = 0; gi < dense.groups.size(); ++gi) {
    const GroupFit& d = dense.groups[gi];
    const GroupFit& s = stream.groups[gi];
    EXPECT_TRUE(d.streamed.empty());
    EXPECT_FALSE(s.streamed.empty());
    EXPECT_TRUE(s.row_time.empty() && s.known.empty() && s.summary.residuals.empty());
    EXPECT_EQ(d.columns, s.columns);
    EXPECT_EQ(d.summary.n, s.summary.n);
    EXPECT_EQ(d.summary.rank, s.summary.rank);
    EXPECT_EQ(d.summary.termination, s.summary.termination);
    EXPECT_EQ(d.weighted, s.weighted);
    ASSERT_EQ(d.regions.size(), s.regions.size());
    for (std::size_t k = 0; k < d.regions.size(); ++k) {
      EXPECT_EQ(d.regions[k].guards, s.regions[k].guards);
      EXPECT_EQ(d.regions[k].rows, s.regions[k].rows);
    }
    ASSERT_EQ(d.records.size(), s.records.size());
    for (std::size_t k = 0; k < d.records.size(); ++k) {
      EXPECT_EQ(d.records[k].rows, s.records[k].rows);
      EXPECT_EQ(d.records[k].t0, s.records[k].t0);
    }
    EXPECT_NEAR(d.summary.G, s.summary.G, 1e-8 * d.summary.G) << "group " << gi;
    EXPECT_EQ(d.summary.r_squared_centred, s.summary.r_squared_centred);
    EXPECT_NEAR(d.summary.r_squared, s.summary.r_squared, 1e-9 + 1e-6 * (1 - d.summary.r_squared)) << "group " << gi;
    EXPECT_NEAR(d.summary.aic, s.summary.aic, 1e-6 * std::abs(d.summary.aic)) << "group " << gi;
    ASSERT_EQ(d.summary.parameters.size(), s.summary.parameters.size());
    for (std::size_t k = 0; k < d.summary.parameters.size(); ++k) {
      const auto& a = d.summary.parameters[k];
      const auto& b = s.summary.parameters[k];
      EXPECT_EQ(a.name, b.name);
      // Rounding of the data is amplified by the condition number (about 10^6 for the thesis'
      // polynomials after scaling); a thousandth of a standard error is far below any meaning.
      EXPECT_NEAR(a.value, b.value, 1e-9 * std::abs(a.value) + 1e-6 * a.standard_error) << a.name;
      EXPECT_NEAR(a.standard_error, b.standard_error, 1e-6 * a.standard_error) << a.name;
    }
  }
}

TEST(StreamedFit, DerivativeFormWithGuardsAndADefinedInput) {
  const ir::Model m = compiled_file(SIDC_SOURCE_DIR "/examples/thesis-4-1/derivative_form.sid");
  const std::vector<SampledRecord> records{appendix_a(m)};
  const FitSummary dense = fitted(m, records, thesis_options());
  ASSERT_FALSE(dense.groups.empty());
  EXPECT_FALSE(dense.groups[0].regions.empty());
  for (std::size_t block : {1, 7, 64, 4096}) {
    SCOPED_TRACE(block);
    expect_same_fit(dense, fitted(m, records, streamed(thesis_options(), block)));
  }
  // One thread, and more threads than blocks.
  expect_same_fit(dense, fitted(m, records, streamed(thesis_options(), 7, 1)));
  expect_same_fit(dense, fitted(m, records, streamed(thesis_options(), 5, 8)));
}

// savgol(auto): each record gets its own arcs (a noisier record no narrower ones); the streamed fit's
// halos follow them and agree with the dense fit.
TEST(StreamedFit, AutomaticArcsPerRecordAgreeWithTheDenseFit) {
  const ir::Model m = compiled_text("auto.sid",
                                    "model auto_arcs\ninput x = 60*sin(4*pi*t)\noutput y\nparam m, c, k, d\n"
                                    "m*y'' + c*y' + k*y + d*der(abs(y)) = x\n");
  std::vector<SampledRecord> records{appendix_a(m), appendix_a(m)};
  // Deterministic noise of about 0.1% and 1% of y's spread on the two records.
  for (std::size_t r = 0; r < 2; ++r) {
    auto& y = records[r].signals.at("y").owned();
    for (std::size_t i = 0; i < y.size(); ++i) y[i] += (r ? 1e-2 : 1e-3) * std::sin(1e3 * static_cast<double>(i) * (1.0 + 0.37 * static_cast<double>(r)));
  }
  FitOptions o;
  o.evaluation.automatic_derivative = true;
  const FitSummary dense = fitted(m, records, o);
  ASSERT_EQ(dense.operators.size(), 2u);
  ASSERT_EQ(dense.operators[0].arcs.size(), 2u);  // y' and y'' (the compiler writes der(abs(y)) as sign(y)*y')
  EXPECT_LE(dense.operators[0].arcs[0].arc.window, dense.operators[1].arcs[0].arc.window);
  // The fit window keeps clear of the widest arc's half-window (edges = drop).
  int lost = 0;
  for (const auto& a : dense.operators[0].arcs) lost = std::max(lost, a.arc.window / 2);
  EXPECT_EQ(dense.groups[0].records[0].first_sample, static_cast<std::size_t>(lost));
  for (std::size_t block : {1, 7, 300}) {
    SCOPED_TRACE(block);
    expect_same_fit(dense, fitted(m, records, streamed(o, block)));
  }
}

TEST(StreamedFit, IntegratedFormSeveralRecordsAndEveryOtherSample) {
  const ir::Model m = compiled_file(SIDC_SOURCE_DIR "/examples/thesis-4-1/quasi_linear.sid");
  // The Delta = 0.010 record and its every-other-sample Delta = 0.020 version: two records, each
  // with its own integration constant.
  const std::vector<SampledRecord> records{appendix_a(m), appendix_a(m, 2)};
  const FitSummary dense = fitted(m, records, thesis_options());
  ASSERT_FALSE(dense.groups.empty());
  EXPECT_EQ(dense.groups[0].records.size(), 2u);
  expect_same_fit(dense, fitted(m, records, streamed(thesis_options())));
  // And each alone (every = 2 alone).
  expect_same_fit(fitted(m, {records[1]}, thesis_options()), fitted(m, {records[1]}, streamed(thesis_options(), 3)));
}

// The progress hook: after every stretch, rows folded so far rising to all of them (both records).
TEST(StreamedFit, TellsItsProgressStretchByStretch) {
  const ir::Model m = compiled_file(SIDC_SOURCE_DIR "/examples/thesis-4-1/quasi_linear.sid");
  const std::vector<SampledRecord> records{appendix_a(m), appendix_a(m, 2)};
  FitOptions o = streamed(thesis_options());
  std::vector<std::pair<std::size_t, std::size_t>> calls;
  o.progress = [&calls](std::size_t done, std::size_t total) { calls.emplace_back(done, total); };
  const FitSummary s = fitted(m, records, o);
  ASSERT_EQ(s.groups.size(), 1u);
  ASSERT_GT(calls.size(), 2u);  // stretches of 22 rows over two records of about 80 and 40 rows
  for (std::size_t k = 1; k < calls.size(); ++k) {
    EXPECT_GT(calls[k].first, calls[k - 1].first);
    EXPECT_EQ(calls[k].second, calls[0].second);
  }
  EXPECT_EQ(calls.back().first, calls.back().second);
  EXPECT_EQ(calls.back().second, s.groups[0].summary.n);
}

TEST(StreamedFit, RowWeightsIncludingZeros) {
  const ir::Model m = compiled_file(SIDC_SOURCE_DIR "/examples/thesis-4-1/quasi_linear.sid");
  SampledRecord r = appendix_a(m);
  r.weights.resize(r.time.size());
  for (std::size_t k = 0; k < r.weights.size(); ++k) r.weights[k] = k % 5 == 0 ? 0.0 : 1.0 + 0.5 * std::sin(0.3 * static_cast<double>(k));
  const FitSummary dense = fitted(m, {r}, thesis_options());
  ASSERT_FALSE(dense.groups.empty());
  EXPECT_TRUE(dense.groups[0].weighted);
  expect_same_fit(dense, fitted(m, {r}, streamed(thesis_options())));
}

TEST(StreamedFit, TwoGroupsAndInitialValues) {
  // Section 4-2's model (two equations sharing no parameter, y2(0) in the operations) on a
  // record made here: a damped response to a square-ish input.
  const ir::Model m = compiled_file(SIDC_SOURCE_DIR "/examples/thesis-4-2/process.sid");
  const SampledRecord r = testing::synthetic_record(300, 0.75, {
      {"x", [](double t) { return std::sin(0.05 * t) > 0 ? 1.0 : -0.5; }},
      {"y1", [](double t) { return std::exp(-0.01 * t) * std::sin(0.11 * t) + 0.01 * std::cos(1.3 * t); }},
      {"y2", [](double t) { return 0.4 + std::cos(0.07 * t) - 0.02 * std::sin(2.1 * t); }}});
  const FitSummary dense = fitted(m, {r}, {});
  ASSERT_EQ(dense.groups.size(), 2u);
  expect_same_fit(dense, fitted(m, {r}, streamed({}, 16)));
}

TEST(StreamedFit, ResidualsInASecondPassMatchTheDenseOnes) {
  const ir::Model m = compiled_file(SIDC_SOURCE_DIR "/examples/thesis-4-1/quasi_linear.sid");
  const std::vector<SampledRecord> records{appendix_a(m), appendix_a(m, 2)};
  const FitOptions dense_options = thesis_options(), stream_options = streamed(thesis_options(), 6);
  const FitSummary dense = fitted(m, records, dense_options);
  const FitSummary stream = fitted(m, records, stream_options);
  std::vector<ResidualRow> a, b;
  ASSERT_FALSE(for_each_residual_block(m, records, dense_options, dense, 0,
                                       [&](std::span<const ResidualRow> rows) {
                                         a.insert(a.end(), rows.begin(), rows.end());
                                         return true;
                                       }));
  ASSERT_FALSE(for_each_residual_block(m, records, stream_options, stream, 0,
                                       [&](std::span<const ResidualRow> rows) {
                                         b.insert(b.end(), rows.begin(), rows.end());
                                         return true;
                                       }));
  ASSERT_EQ(a.size(), dense.groups[0].row_time.size());
  ASSERT_EQ(a.size(), b.size());
  double largest = 0;
  for (const auto& row : a) largest = std::max(largest, std::abs(row.residual));
  ASSERT_GT(largest, 0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].equation, b[i].equation);
    EXPECT_EQ(a[i].record, b[i].record);
    EXPECT_EQ(a[i].time, b[i].time);
    EXPECT_DOUBLE_EQ(a[i].known, b[i].known);
    EXPECT_NEAR(a[i].residual, b[i].residual, 1e-7 * largest) << "row " << i;
  }
}

TEST(StreamedFit, ResidualsOfBlocksEvaluatedOnTheCoresMatchTheDenseOnes) {
  // Blocks large enough, and a design wide enough, for the second pass to evaluate a batch of
  // blocks on the cores (fit.cpp, for_each_residual_block): handed on in order, each as the dense fit has it.
  const ir::Model m = compiled_text("library.sid", "input x\noutput y\nparam m, c[1..6], s[1..6], d[1..7]\n"
                                                   "set derivative = savgol(7, 3)\n"
                                                   "m*y'' + sum(k = 1..6, c[k]*y'^k) + sum(k = 1..6, s[k]*y^k) + sum(k = 1..7, d[k]*y^k*y') = x\n");
  const SampledRecord r = testing::synthetic_record(60000, 0.001, {
      {"x", [](double t) { return std::sin(1.3 * t) + 0.4 * std::cos(3.7 * t); }},
      {"y", [](double t) { return 0.8 * std::sin(1.1 * t + 0.2) + 0.3 * std::sin(2.9 * t) + 1e-4 * std::cos(41.0 * t); }}});
  FitOptions stream_options;
  stream_options.stream_above_entries = 0;
  stream_options.stream_block_rows = 2048;
  const FitSummary dense = fitted(m, {r}, {});
  const FitSummary stream = fitted(m, {r}, stream_options);
  std::vector<ResidualRow> a, b;
  std::size_t handed = 0;
  ASSERT_FALSE(for_each_residual_block(m, {r}, {}, dense, 0, [&](std::span<const ResidualRow> rows) {
    a.insert(a.end(), rows.begin(), rows.end());
    return true;
  }));
  ASSERT_FALSE(for_each_residual_block(m, {r}, stream_options, stream, 0, [&](std::span<const ResidualRow> rows) {
    b.insert(b.end(), rows.begin(), rows.end());
    ++handed;
    return true;
  }));
  ASSERT_EQ(a.size(), b.size());
  EXPECT_GT(handed, 16u);  // two batches of blocks at least
  double largest = 0;
  for (const auto& row : a) largest = std::max(largest, std::abs(row.residual));
  ASSERT_GT(largest, 0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].time, b[i].time) << "row " << i;
    EXPECT_DOUBLE_EQ(a[i].known, b[i].known) << "row " << i;
    EXPECT_NEAR(a[i].residual, b[i].residual, 1e-6 * largest) << "row " << i;
  }
  // Stopped after the first block: later batches are not handed on.
  handed = 0;
  ASSERT_FALSE(for_each_residual_block(m, {r}, stream_options, stream, 0, [&](std::span<const ResidualRow>) { return ++handed < 1; }));
  EXPECT_EQ(handed, 1u);
}

TEST(StreamedFit, TheSameDiagnosticForAValueThatIsNotFinite) {
  // log(y) is NaN where y < 0: both paths must blame the same term at the same time.
  const ir::Model m = compiled_text("log.sid", "input x\noutput y\nparam a, b\nset to = 0.82\na*y' + b*log(y + 1) = x\n");
  SampledRecord r = appendix_a(m);
  for (double& y : r.signals["y"].owned()) y -= 0.8;  // y + 1 < 0 somewhere inside the window
  const auto dense = fit(m, {r}, thesis_options());
  const auto stream = fit(m, {r}, streamed(thesis_options(), 3));
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(dense));
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(stream));
  EXPECT_EQ(render(std::get<Diagnostic>(dense)), render(std::get<Diagnostic>(stream)));
  EXPECT_NE(render(std::get<Diagnostic>(dense)).find("log"), std::string::npos) << render(std::get<Diagnostic>(dense));
}

TEST(BlockEvaluator, BlocksGiveTheWholeRecordsValuesBitForBit) {
  // Every operation of the integrated thesis model, with `shorten` edges too: the block values
  // equal Evaluator's on the whole record, bit for bit (powers y^3, y^5 included: the same ladder).
  for (const auto edges : {DerivativeOptions::Edges::drop, DerivativeOptions::Edges::shorten}) {
    const ir::Model m = compiled_file(SIDC_SOURCE_DIR "/examples/thesis-4-1/quasi_linear.sid");
    const SampledRecord r = appendix_a(m);
    EvaluationOptions options;
    options.derivative.edges = edges;
    auto window = fit_window(r, m, options, std::nullopt, 0.82);
    ASSERT_TRUE(std::holds_alternative<FitWindow>(window));
    const FitWindow w = std::get<FitWindow>(window);
    Evaluator whole(r, m, options, w);
    std::vector<const ir::Sum*> sums;
    for (const auto& p : m.equations[0].terms) sums.push_back(&p.operation);
    sums.push_back(&m.equations[0].known);
    auto prepared = prepare_whole_window_values(r, m, options, w, sums);
    ASSERT_TRUE(std::holds_alternative<WholeWindowValues>(prepared));
    BlockEvaluator blocks(r, options, w, std::get<WholeWindowValues>(prepared));
    for (const ir::Sum* s : sums) {
      auto expected = whole.evaluate_in_window(*s, "test");
      ASSERT_TRUE(std::holds_alternative<std::vector<double>>(expected));
      const auto& e = std::get<std::vector<double>>(expected);
      std::vector<double> got(e.size());
      for (std::size_t start = 0; start < w.size(); start += 5) {
        const std::size_t m_rows = std::min<std::size_t>(5, w.size() - start);
        blocks.start_block(w.first + start, w.first + start + m_rows);
        auto status = blocks.evaluate(*s, std::span<double>(got.data() + start, m_rows));
        ASSERT_FALSE(std::holds_alternative<Diagnostic>(status));
      }
      for (std::size_t i = 0; i < e.size(); ++i) EXPECT_EQ(got[i], e[i]) << i;
    }
  }
}

}  // namespace
}  // namespace sidc

namespace sidc {
namespace {

// y = sin(2t + 0.3) + 0.3 sin(3.1t), x = 0.5 y' + 2 y + a little structured misfit, so that the
// weights change the estimates.
SampledRecord weighted_test_record() {
  SampledRecord r;
  r.path = "synthetic";
  r.step = 1e-3;
  for (int k = 0; k < 3001; ++k) {
    const double t = 1e-3 * k;
    const double y = std::sin(2 * t + 0.3) + 0.3 * std::sin(3.1 * t);
    const double dy = 2 * std::cos(2 * t + 0.3) + 0.93 * std::cos(3.1 * t);
    r.time.push_back(t);
    r.signals["y"].push_back(y);
    r.signals["x"].push_back(0.5 * dy + 2 * y + 0.05 * y * y * y);
  }
  return r;
}

TEST(WeightsExpression, EqualsTheSameWeightsGivenAsAColumn) {
  const ir::Model by_expression = compiled_text("w.sid", "input x\noutput y\nparam a1, a2\nset weights = 1 + y^2\na1*y' + a2*y = x\n");
  const ir::Model plain = compiled_text("p.sid", "input x\noutput y\nparam a1, a2\na1*y' + a2*y = x\n");
  ASSERT_TRUE(by_expression.weights.has_value());
  const SampledRecord r = weighted_test_record();
  SampledRecord with_column = r;
  for (double y : r.signals.at("y")) with_column.weights.push_back(1 + y * y);
  const FitSummary expression = fitted(by_expression, {r}, {});
  const FitSummary column = fitted(plain, {with_column}, {});
  const FitSummary unweighted = fitted(plain, {r}, {});
  ASSERT_EQ(expression.groups.size(), 1u);
  ASSERT_EQ(column.groups.size(), 1u);
  EXPECT_TRUE(expression.groups[0].weighted);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(expression.groups[0].summary.parameters[k].value, column.groups[0].summary.parameters[k].value);
    EXPECT_EQ(expression.groups[0].summary.parameters[k].standard_error, column.groups[0].summary.parameters[k].standard_error);
    // The weights matter: the unweighted fit differs.
    EXPECT_NE(expression.groups[0].summary.parameters[k].value, unweighted.groups[0].summary.parameters[k].value);
  }
  EXPECT_EQ(expression.groups[0].summary.G, column.groups[0].summary.G);
  EXPECT_NE(expression.full_report(by_expression).find("weighted by `y^2 + 1`"), std::string::npos)
      << expression.full_report(by_expression);
  // And streamed.
  expect_same_fit(expression, fitted(by_expression, {r}, streamed({}, 100)));
  expect_same_fit(column, fitted(plain, {with_column}, streamed({}, 100)));
}

TEST(WeightsExpression, ANegativeWeightIsAnErrorAtTheExpression) {
  const std::string text = "input x\noutput y\nparam a1, a2\nset weights = y\na1*y' + a2*y = x\n";
  const ir::Model m = compiled_text("neg.sid", text);
  const SampledRecord r = weighted_test_record();  // y < 0 somewhere
  const auto dense = fit(m, {r}, {});
  const auto stream = fit(m, {r}, streamed({}, 64));
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(dense));
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(stream));
  const std::string message = render(std::get<Diagnostic>(dense));
  EXPECT_NE(message.find("neg.sid:4:"), std::string::npos) << message;  // the `set weights` line
  EXPECT_NE(message.find("finite number >= 0"), std::string::npos) << message;
  EXPECT_EQ(message, render(std::get<Diagnostic>(stream)));
}

}  // namespace
}  // namespace sidc

namespace sidc {
namespace {

TEST(BindRecord, MovingTheRecordGivesWhatCopyingGives) {
  const ir::Model m = compiled_text("b.sid", "input x\noutput y\nparam a1, a2\na1*y' + a2*y = x\n");
  const std::string text = "t,x,y\n0,1,2\n0.1,1.5,2.5\n0.2,1.25,2.75\n0.3,1,3\n0.4,0.5,3.5\n";
  for (int every : {1, 2}) {
    auto read = parse_csv(text, "mem.csv");
    ASSERT_TRUE(std::holds_alternative<Record>(read));
    const Record record = std::get<Record>(read);
    ir::DataSource source;
    BindOptions options;
    options.every = every;
    options.weights = "y";  // the column `y` is taken twice: as the signal and as the weights
    auto copied = bind_record(record, source, m, options);
    Record given = record;
    auto moved = bind_record(std::move(given), source, m, options);
    ASSERT_TRUE(std::holds_alternative<SampledRecord>(copied) && std::holds_alternative<SampledRecord>(moved));
    const auto& a = std::get<SampledRecord>(copied);
    const auto& b = std::get<SampledRecord>(moved);
    EXPECT_EQ(a.time, b.time);
    EXPECT_EQ(a.step, b.step);
    EXPECT_EQ(a.signals, b.signals);
    EXPECT_EQ(a.weights, b.weights);
    EXPECT_EQ(a.weights, a.signals.at("y"));
    EXPECT_EQ(a.time.size(), every == 1 ? 5u : 3u);
  }
}

// Records handed over in memory (the Python module's numpy arrays) are borrowed, not copied: the
// bound record reads the lender's memory, and a column written to makes its own copy first.
TEST(BindRecord, BorrowedColumnsAreReadInPlaceAndNeverWritten) {
  const ir::Model m = compiled_text("b.sid", "input x\noutput y\nparam a1, a2\na1*y' + a2*y = x\n");
  const std::vector<std::vector<double>> lent{{0, 0.1, 0.2, 0.3, 0.4}, {1, 1.5, 1.25, 1, 0.5}, {2, 2.5, 2.75, 3, 3.5}};
  auto keep_alive = std::make_shared<int>(0);
  const auto as_record = [&] {
    Record r;
    r.path = "<arrays>";
    r.names = {"t", "x", "y"};
    for (const auto& values : lent) r.columns.push_back(Column::borrowed(values, keep_alive));
    r.first_faults.resize(3);
    r.line_jumps = {{0, 0}};
    return r;
  };
  auto copied_text = parse_csv("t,x,y\n0,1,2\n0.1,1.5,2.5\n0.2,1.25,2.75\n0.3,1,3\n0.4,0.5,3.5\n", "mem.csv");
  ASSERT_TRUE(std::holds_alternative<Record>(copied_text));
  for (int every : {1, 2}) {
    BindOptions options;
    options.every = every;
    auto borrowed = bind_record(as_record(), ir::DataSource{}, m, options);
    auto owned = bind_record(std::get<Record>(copied_text), ir::DataSource{}, m, options);
    ASSERT_TRUE(std::holds_alternative<SampledRecord>(borrowed) && std::holds_alternative<SampledRecord>(owned));
    const auto& b = std::get<SampledRecord>(borrowed);
    const auto& o = std::get<SampledRecord>(owned);
    EXPECT_EQ(b.time, o.time);
    EXPECT_EQ(b.signals, o.signals);
    // Every sample kept: the very memory lent; every other one: columns of its own.
    EXPECT_EQ(b.signals.at("y").data() == lent[2].data(), every == 1);
    EXPECT_EQ(b.time.is_borrowed(), every == 1);
    EXPECT_EQ(keep_alive.use_count(), every == 1 ? 4 : 1);  // t, x, y hold it, besides this test
  }
  EXPECT_EQ(keep_alive.use_count(), 1);  // released with the last column

  Column y = Column::borrowed(lent[2], keep_alive);
  const Column shared = y;  // a copy shares the borrowed memory
  EXPECT_EQ(shared.data(), lent[2].data());
  y.owned()[0] = -1;  // written: a copy of its own first
  EXPECT_EQ(lent[2][0], 2);
  EXPECT_EQ(y[0], -1);
  EXPECT_NE(y.data(), lent[2].data());
  EXPECT_EQ(shared[0], 2);
  EXPECT_EQ(std::move(y).release(), (std::vector<double>{-1, 2.5, 2.75, 3, 3.5}));
}

}  // namespace
}  // namespace sidc
