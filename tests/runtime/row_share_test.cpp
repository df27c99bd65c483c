// A streamed fit's rows shared among parts (runtime/solve/row_share.hpp, FitOptions::share): the
// parts here are threads of this process that merge their factors through memory, which is what
// distributed/'s MPI share does between processes (tests/distributed/ runs that one under mpirun).
// Every part must end with the fit one process makes: the same estimates to rounding, the same
// rows, regions and records; and a problem met in one part's rows must be named by every part as
// one process names it. The accumulator's state must travel exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <span>
#include <thread>
#include <utility>

#include "runtime/select/select.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/solve/row_share.hpp"
#include "runtime/solve/triangular_accumulator.hpp"

#include "support/shell.hpp"
#include "support/synthetic_record.hpp"
#include "support/thread_share.hpp"
#include "support/thesis_record.hpp"

namespace sidc {
namespace {

// Every part's fit.
std::vector<std::variant<FitSummary, Diagnostic>> fit_in_parts(const ir::Model& m, const std::vector<SampledRecord>& records,
                                                               const FitOptions& o, int parts, int* problem_rounds = nullptr,
                                                               int* sums = nullptr) {
  ThreadRoom room(parts);
  auto results = in_parts(room, [&](RowShare& share, int) {
    FitOptions mine = o;
    mine.share = &share;
    return fit(m, records, mine);
  });
  if (problem_rounds) *problem_rounds = room.problem_rounds;
  if (sums) *sums = room.sums;
  return results;
}

FitOptions streamed_in_blocks(std::size_t block_rows) {
  FitOptions o;
  o.to = 0.82;  // the thesis models' `set to`
  o.stream_above_entries = 0;
  o.stream_block_rows = block_rows;
  o.stream_threads = 1;
  o.stream_stretch_rows = 3 * block_rows + 1;  // integrals carried over many stretches
  return o;
}

void expect_same_as_one_process(const FitSummary& one, const FitSummary& part) {
  ASSERT_EQ(one.groups.size(), part.groups.size());
  for (std::size_t gi = 0; gi < one.groups.size(); ++gi) {
    const GroupFit& a = one.groups[gi];
    const GroupFit& b = part.groups[gi];
    EXPECT_EQ(a.summary.n, b.summary.n);
    EXPECT_EQ(a.summary.rank, b.summary.rank);
    ASSERT_EQ(a.regions.size(), b.regions.size());
    for (std::size_t k = 0; k < a.regions.size(); ++k) {
      EXPECT_EQ(a.regions[k].guards, b.regions[k].guards);
      EXPECT_EQ(a.regions[k].rows, b.regions[k].rows);
    }
    ASSERT_EQ(a.records.size(), b.records.size());
    for (std::size_t k = 0; k < a.records.size(); ++k) EXPECT_EQ(a.records[k].rows, b.records[k].rows);
    EXPECT_NEAR(a.summary.G, b.summary.G, 1e-9 * a.summary.G);
    ASSERT_EQ(a.summary.parameters.size(), b.summary.parameters.size());
    for (std::size_t k = 0; k < a.summary.parameters.size(); ++k) {
      const auto& x = a.summary.parameters[k];
      const auto& y = b.summary.parameters[k];
      // Another order of Householder merges: rounding, amplified by the condition number.
      EXPECT_NEAR(x.value, y.value, 1e-9 * std::abs(x.value) + 1e-6 * x.standard_error) << x.name;
      EXPECT_NEAR(x.standard_error, y.standard_error, 1e-6 * x.standard_error) << x.name;
    }
  }
}

void expect_parts_agree(const ir::Model& m, const std::vector<SampledRecord>& records, const FitOptions& o) {
  auto single = fit(m, records, o);
  ASSERT_TRUE(std::holds_alternative<FitSummary>(single)) << render(std::get<Diagnostic>(single));
  const FitSummary& one = std::get<FitSummary>(single);
  for (int parts : {2, 3, 5}) {
    SCOPED_TRACE(parts);
    const auto results = fit_in_parts(m, records, o, parts);
    for (const auto& r : results) {
      ASSERT_TRUE(std::holds_alternative<FitSummary>(r)) << render(std::get<Diagnostic>(r));
      expect_same_as_one_process(one, std::get<FitSummary>(r));
      EXPECT_NE(std::get<FitSummary>(r).groups[0].streamed.find(std::to_string(parts) + " processes"), std::string::npos);
    }
    // The parts among themselves: the same bits.
    for (std::size_t k = 1; k < results.size(); ++k)
      for (std::size_t j = 0; j < one.groups[0].summary.parameters.size(); ++j)
        EXPECT_EQ(std::get<FitSummary>(results[0]).groups[0].summary.parameters[j].value,
                  std::get<FitSummary>(results[k]).groups[0].summary.parameters[j].value);
  }
}

TEST(RowShare, AccumulatorStateTravelsExactly) {
  std::mt19937_64 random(7);
  std::normal_distribution<double> normal;
  TriangularAccumulator a(4);
  Eigen::MatrixXd rows(300, 4);
  Eigen::VectorXd b(300), w(300);
  for (int i = 0; i < 300; ++i) {
    for (int j = 0; j < 4; ++j) rows(i, j) = normal(random) * std::pow(10.0, j);
    b(i) = normal(random);
    w(i) = 0.5 + std::abs(normal(random));
  }
  rows.col(2).setConstant(3.0);  // a constant column: its mark travels too
  ASSERT_TRUE(a.add_rows(rows, b, &w));
  TriangularAccumulator copy(4);
  ASSERT_TRUE(copy.from_doubles(a.to_doubles()));
  EXPECT_EQ(copy.to_doubles(), a.to_doubles());
  const std::vector<std::string> names{"a", "b", "c", "d"};
  const LeastSquaresSummary x = a.solve(names, {}), y = copy.solve(names, {});
  ASSERT_EQ(x.parameters.size(), y.parameters.size());
  for (std::size_t k = 0; k < x.parameters.size(); ++k) EXPECT_EQ(x.parameters[k].value, y.parameters[k].value);
  EXPECT_EQ(x.r_squared_centred, y.r_squared_centred);
  EXPECT_EQ(x.n, y.n);
  // The wrong size is refused, not read.
  TriangularAccumulator other(3);
  std::string why;
  EXPECT_FALSE(other.from_doubles(a.to_doubles(), &why));
  EXPECT_FALSE(why.empty());
}

TEST(RowShare, DerivativeFormWithGuardsAsOneProcessFitsIt) {
  const ir::Model m = testing::compiled_text("d.sid", testing::read_text(SIDC_SOURCE_DIR "/examples/thesis-4-1/derivative_form.sid"));
  expect_parts_agree(m, {testing::appendix_a(m)}, streamed_in_blocks(5));
}

TEST(RowShare, IntegratedFormOverTwoRecordsAsOneProcessFitsIt) {
  const ir::Model m = testing::compiled_text("q.sid", testing::read_text(SIDC_SOURCE_DIR "/examples/thesis-4-1/quasi_linear.sid"));
  expect_parts_agree(m, {testing::appendix_a(m), testing::appendix_a(m, 2)}, streamed_in_blocks(4));
}

// With as many records as parts, each part folds whole records (no integral carried from the start of
// a record another part folds too): the thesis record (its rows to t = 0.82) and its every-other-
// sample copy, about 80 and 40 rows, go one to each part. The progress hook tells each part's rows.
TEST(RowShare, RecordsGoWholeToThePartsWhenThereAreEnough) {
  const ir::Model m = testing::compiled_text("q.sid", testing::read_text(SIDC_SOURCE_DIR "/examples/thesis-4-1/quasi_linear.sid"));
  const std::vector<SampledRecord> records{testing::appendix_a(m), testing::appendix_a(m, 2)};
  auto single = fit(m, records, streamed_in_blocks(4));
  ASSERT_TRUE(std::holds_alternative<FitSummary>(single));
  const auto& rows = std::get<FitSummary>(single).groups[0].records;
  ASSERT_EQ(rows.size(), 2u);
  ThreadRoom room(2);
  std::vector<std::size_t> totals(2, 0);
  const auto results = in_parts(room, [&](RowShare& share, int k) {
    FitOptions o = streamed_in_blocks(4);
    o.share = &share;
    o.progress = [&totals, k](std::size_t, std::size_t total) { totals[static_cast<std::size_t>(k)] = total; };
    return fit(m, records, o);
  });
  for (const auto& r : results) EXPECT_TRUE(std::holds_alternative<FitSummary>(r));
  EXPECT_EQ(totals[0], rows[0].rows);
  EXPECT_EQ(totals[1], rows[1].rows);
}

// A value that cannot be evaluated in the last part's rows only: every part names the problem one
// process names (the same text), none a problem of its own share.
TEST(RowShare, AProblemInOnePartIsNamedAsOneProcessNamesIt) {
  const ir::Model m = testing::compiled_text("d.sid", testing::read_text(SIDC_SOURCE_DIR "/examples/thesis-4-1/derivative_form.sid"));
  SampledRecord r = testing::appendix_a(m);
  auto& y = r.signals.at("y").owned();
  y[y.size() * 3 / 4] = std::nan("");
  const FitOptions o = streamed_in_blocks(5);
  auto single = fit(m, {r}, o);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(single));
  int problem_rounds = 0;
  const auto results = fit_in_parts(m, {r}, o, 3, &problem_rounds);
  EXPECT_EQ(problem_rounds, 1) << "the problem was to be met in a part's rows, not before the rows were shared";
  for (const auto& result : results) {
    ASSERT_TRUE(std::holds_alternative<Diagnostic>(result));
    EXPECT_EQ(render(std::get<Diagnostic>(result)), render(std::get<Diagnostic>(single)));
  }
}

// The weak form: each part integrates the subdomains whose supports start in its blocks of the
// window (2^15 samples each), and the parts' rows are summed; every part has one process's design,
// bit for bit, and so the same estimates exactly. A record of 10^5 samples: four blocks.
TEST(RowShare, WeakFormRowsAreOneProcessesBitForBit) {
  const ir::Model m = testing::compiled_text("w.sid",
                                             "model weak_shared\ninput x\noutput y\nparam m, c, k\nset form = weak\n"
                                             "m*y'' + c*y' + k*y = x\n");
  const SampledRecord r = testing::synthetic_record(100000, 0.001, {
      {"x", [](double t) { return std::sin(1.3 * t) + 0.5 * std::sin(3.1 * t); }},
      {"y", [](double t) { return std::exp(-0.05 * t) * std::sin(2.0 * t) + 0.2 * std::sin(1.3 * t - 0.4) + 1e-4 * std::sin(977.0 * t); }}});
  FitOptions o;
  auto single = fit(m, {r}, o);
  ASSERT_TRUE(std::holds_alternative<FitSummary>(single)) << render(std::get<Diagnostic>(single));
  const FitSummary& one = std::get<FitSummary>(single);
  int sums = 0;
  for (const auto& result : fit_in_parts(m, {r}, o, 3, nullptr, &sums)) {
    ASSERT_TRUE(std::holds_alternative<FitSummary>(result)) << render(std::get<Diagnostic>(result));
    const FitSummary& part = std::get<FitSummary>(result);
    ASSERT_EQ(part.groups.size(), 1u);
    EXPECT_EQ(part.groups[0].summary.n, one.groups[0].summary.n);
    for (std::size_t k = 0; k < one.groups[0].summary.parameters.size(); ++k)
      EXPECT_EQ(part.groups[0].summary.parameters[k].value, one.groups[0].summary.parameters[k].value);
  }
  EXPECT_GE(sums, 4) << "the weak rows were to be shared: one sum per operation";
}

// sidc select's streamed rows: each part folds its share of the window into the time blocks'
// triangles and line sums, merged in part order; every part selects what one process selects.
TEST(RowShare, SelectionAsOneProcessSelects) {
  const ir::Model m = testing::compiled_text("q.sid", testing::read_text(SIDC_SOURCE_DIR "/examples/thesis-4-1/select_sixth.sid"));
  const std::vector<SampledRecord> records{testing::appendix_a(m), testing::appendix_a(m, 2)};
  SelectOptions o;
  o.method = SelectionMethod::stlsq;  // the rows are what is shared; the search is any (exact: seconds)
  o.fit.stream_above_entries = 0;
  o.fit.stream_block_rows = 5;
  o.fit.stream_threads = 1;
  o.fit.stream_stretch_rows = 16;
  auto single = select_operations(m, records, o);
  ASSERT_TRUE(std::holds_alternative<SelectSummary>(single)) << render(std::get<Diagnostic>(single));
  const SelectSummary& one = std::get<SelectSummary>(single);
  ASSERT_TRUE(one.ok()) << one.message;
  ThreadRoom room(3);
  const auto results = in_parts(room, [&](RowShare& share, int) {
    SelectOptions mine = o;
    mine.fit.share = &share;
    return select_operations(m, records, mine);
  });
  for (const auto& result : results) {
    ASSERT_TRUE(std::holds_alternative<SelectSummary>(result)) << render(std::get<Diagnostic>(result));
    const SelectSummary& part = std::get<SelectSummary>(result);
    ASSERT_EQ(part.groups.size(), one.groups.size());
    for (std::size_t g = 0; g < one.groups.size(); ++g) {
      EXPECT_EQ(part.groups[g].n, one.groups[g].n);
      EXPECT_EQ(part.groups[g].chosen, one.groups[g].chosen);
      ASSERT_EQ(part.groups[g].rows.size(), one.groups[g].rows.size());
      for (std::size_t k = 0; k < one.groups[g].rows.size(); ++k) {
        EXPECT_EQ(part.groups[g].rows[k].parameters, one.groups[g].rows[k].parameters);
        EXPECT_NEAR(part.groups[g].rows[k].G, one.groups[g].rows[k].G, 1e-8 * one.groups[g].rows[k].G);
      }
      ASSERT_EQ(part.groups[g].drift.size(), one.groups[g].drift.size());
      for (std::size_t k = 0; k < one.groups[g].drift.size(); ++k)
        EXPECT_NEAR(part.groups[g].drift[k].share, one.groups[g].drift[k].share, 1e-10);
    }
  }
}

}  // namespace
}  // namespace sidc
