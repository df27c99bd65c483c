// Tests of runtime/solve/design.hpp: the columns and their parameter indices, where an equation's
// rows land, the weights of eq. 2-1.6, and the indices on a fit's estimates (dense and streamed)
// and on select's subsets.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "compiler/pipeline.hpp"
#include "runtime/select/select.hpp"
#include "runtime/solve/design.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {
namespace {

ir::Model design_model(const std::string& text) {
  const auto r = compile(std::make_shared<const SourceFile>("design_test.sid", text), {});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return r.ok() ? *r.integrated : ir::Model{};
}

// x = 0.5 y' + 2 y exactly, y = sin(2t + phase) + 0.3 sin(3.1t).
SampledRecord record(double phase, std::size_t n) {
  SampledRecord r;
  r.path = "synthetic";
  r.step = 1e-3;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * 1e-3;
    const double y = std::sin(2 * t + phase) + 0.3 * std::sin(3.1 * t);
    r.time.push_back(t);
    r.signals["y"].push_back(y);
    r.signals["x"].push_back(0.5 * (2 * std::cos(2 * t + phase) + 0.93 * std::cos(3.1 * t)) + 2 * y);
  }
  return r;
}

const char* kIntegrated = "input x\noutput y\nparam a1, a2\nset integrate = 1\na1*y' + a2*y = x\n";

TEST(Design, ColumnsCarryTheirParameterAndRecord) {
  const ir::Model m = design_model(kIntegrated);
  const std::vector<SampledRecord> records{record(0.3, 501), record(1.7, 401)};
  const DesignBuilder design(m, records, {0});
  EXPECT_EQ(design.column_names(), (std::vector<std::string>{"a1", "a2", "C1@1", "C1@2"}));
  const std::vector<ParameterIndex> expected{{0, std::nullopt}, {1, std::nullopt}, {2, 0}, {2, 1}};
  EXPECT_EQ(design.column_indices(), expected);
  EXPECT_EQ(design.column(0, 1), 0u);
  EXPECT_EQ(design.column(2, 0), 2u);
  EXPECT_EQ(design.column(2, 1), 3u);
  // One record: the constant is one column, named as in the model.
  const std::vector<SampledRecord> one{records[0]};
  EXPECT_EQ(DesignBuilder(m, one, {0}).column_names(), (std::vector<std::string>{"a1", "a2", "C1"}));
}

// Fills each sum's rows with its index + 1, so that the columns show which sum went where.
class IndexValues final : public DesignValues {
 public:
  std::optional<Diagnostic> evaluate(const ir::Sum&, std::size_t index, const std::string& what, std::span<double> out) override {
    owners.push_back(what);
    for (double& v : out) v = static_cast<double>(index + 1);
    return std::nullopt;
  }
  std::vector<std::string> owners;
};

TEST(Design, AnEquationsRowsGoToItsParametersColumnsForItsRecord) {
  const ir::Model m = design_model(kIntegrated);
  const std::vector<SampledRecord> records{record(0.3, 501), record(1.7, 401)};
  const DesignBuilder design(m, records, {0});
  Eigen::MatrixXd A = Eigen::MatrixXd::Constant(3, 4, -1.0);
  Eigen::VectorXd b(3);
  IndexValues values;
  ASSERT_FALSE(design.equation_rows(1, 0, values, {A, b}));
  // Terms in the model's order: a1's, a2's, then C1's (record 2's column); the known side last.
  for (Eigen::Index i = 0; i < 3; ++i) {
    EXPECT_EQ(A(i, 0), 1.0);
    EXPECT_EQ(A(i, 1), 2.0);
    EXPECT_EQ(A(i, 2), -1.0);  // record 1's constant: not this record's, left alone
    EXPECT_EQ(A(i, 3), 3.0);
    EXPECT_EQ(b(i), 4.0);
  }
  EXPECT_EQ(values.owners, (std::vector<std::string>{"the operation of `a1`", "the operation of `a2`", "the operation of `C1`",
                                                     "the known side"}));
}

TEST(Design, RowWeightsAreTheColumnTimesTheExpression) {
  const ir::Model m = design_model(kIntegrated);
  std::vector<SampledRecord> records{record(0.3, 10)};
  const DesignBuilder unweighted(m, records, {0});
  std::vector<double> out(3);
  const std::vector<double> expression{2, 3, 4};
  EXPECT_EQ(unweighted.row_weights(0, 4, {}, out), nullptr);
  EXPECT_EQ(unweighted.row_weights(0, 4, expression, out), expression.data());
  records[0].weights = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
  const DesignBuilder weighted(m, records, {0});
  EXPECT_EQ(weighted.row_weights(0, 4, {}, out), records[0].weights.data() + 4);
  const double* w = weighted.row_weights(0, 4, expression, out);
  ASSERT_EQ(w, out.data());
  EXPECT_EQ(out, (std::vector<double>{8, 15, 24}));
}

TEST(Design, EstimatesCarryTheirParameterIndexDenseAndStreamed) {
  const ir::Model m = design_model(kIntegrated);
  const std::vector<SampledRecord> records{record(0.3, 2001), record(1.7, 1501)};
  FitOptions streamed;
  streamed.stream_above_entries = 0;
  streamed.stream_block_rows = 64;
  for (const FitOptions& options : {FitOptions{}, streamed}) {
    auto result = fit(m, records, options);
    ASSERT_TRUE(std::holds_alternative<FitSummary>(result)) << render(std::get<Diagnostic>(result));
    const GroupFit& g = std::get<FitSummary>(result).groups.at(0);
    ASSERT_EQ(g.column_parameters.size(), g.columns.size());
    ASSERT_EQ(g.summary.parameters.size(), g.columns.size());
    for (std::size_t j = 0; j < g.columns.size(); ++j) {
      const ParameterEstimate& p = g.summary.parameters[j];
      ASSERT_TRUE(p.index.has_value()) << p.name;
      EXPECT_EQ(*p.index, g.column_parameters[j]);
      const std::string& name = m.parameters[p.index->parameter].name;
      EXPECT_EQ(p.name, p.index->record ? name + "@" + std::to_string(*p.index->record + 1) : name);
    }
    EXPECT_NEAR(g.summary.parameters[0].value, 0.5, 1e-6);
    EXPECT_NEAR(g.summary.parameters[1].value, 2.0, 1e-6);
  }
}

TEST(Design, SelectionsCarryTheSameIndices) {
  const ir::Model m = design_model("input x\noutput y\nparam a1, a2, a3\nset integrate = 1\na1*y' + a2*y + a3*y^3 = x\n");
  const std::vector<SampledRecord> records{record(0.3, 2001), record(1.7, 1501)};
  auto result = select_operations(m, records, {});
  ASSERT_TRUE(std::holds_alternative<SelectSummary>(result)) << render(std::get<Diagnostic>(result));
  const GroupSelection& g = std::get<SelectSummary>(result).groups.at(0);
  EXPECT_EQ(g.column_parameters, DesignBuilder(m, records, {0}).column_indices());
  ASSERT_FALSE(g.rows.empty());
  for (const SizeRow& row : g.rows) {
    ASSERT_EQ(row.indices.size(), row.parameters.size());
    for (std::size_t j = 0; j < row.parameters.size(); ++j) {
      const auto c = std::find(g.columns.begin(), g.columns.end(), row.parameters[j]) - g.columns.begin();
      EXPECT_EQ(row.indices[j], g.column_parameters[static_cast<std::size_t>(c)]) << row.parameters[j];
    }
  }
  // y^3 is not in the system: the only operation left out.
  EXPECT_EQ(g.non_contributory, std::vector<std::string>{"a3"});
}

}  // namespace
}  // namespace sidc
