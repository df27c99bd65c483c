// sidc as a library: a model file compiled, fitted to a record, and its estimates printed, as
// `sidc fit MODEL.sid --data RECORD.csv` does without its reports and validation. The record's
// columns are bound to the signals as the model's data statement says, and the model's settings
// (`set derivative = ...`, `set to = ...`) become the fit's options through the same translation
// the sidc command uses (runtime/solve/options_from_settings.hpp).
#include <fmt/format.h>
#include <iostream>

#include "compiler/pipeline.hpp"
#include "runtime/records/bind_record.hpp"
#include "runtime/solve/options_from_settings.hpp"

using namespace sidc;

int fail(const std::string& message) {
  std::cerr << message << "\n";
  return 1;
}

int main(int argc, char** argv) {
  if (argc != 3) return fail("usage: sidc_library_example MODEL.sid RECORD.csv");
  std::string error;
  auto text = read_whole_file(argv[1], error);
  if (!text) return fail(error);
  CompileResult compiled = compile(std::make_shared<const SourceFile>(argv[1], std::move(*text)), {});
  std::cerr << compiled.diagnostics.render_all();  // errors and warnings, as sidc shows them
  if (!compiled.ok()) return 1;
  const ir::Model& model = *compiled.integrated;  // the equations as fitted (`set integrate`)
  const EvaluationSettings settings = evaluation_settings(model.settings);

  ir::DataSource data = model.data.empty() ? ir::DataSource{} : model.data.front();  // column -> signal
  data.path = argv[2];
  auto record = read_csv(data.path);
  if (auto* d = std::get_if<Diagnostic>(&record)) return fail(render(*d));
  auto bound = bind_record(std::get<Record>(std::move(record)), data, model, bind_options(settings));
  if (auto* d = std::get_if<Diagnostic>(&bound)) return fail(render(*d));

  auto result = fit(model, {std::get<SampledRecord>(std::move(bound))}, fit_options(settings));
  if (auto* d = std::get_if<Diagnostic>(&result)) return fail(render(*d));
  const FitSummary& summary = std::get<FitSummary>(result);
  for (const GroupFit& group : summary.groups) {
    for (const ParameterEstimate& p : group.summary.parameters)
      std::cout << fmt::format("{:<8} = {:<14.6g} (standard error {:.3g})\n", p.name, p.value, p.standard_error);
    std::cout << fmt::format("G(a) = {:.6g} over {} rows, rank {} of {}\n", group.summary.G, group.summary.n, group.summary.rank,
                             group.summary.p);
  }
  return summary.is_solution_usable() ? 0 : fail("error: rank deficient: some operations are (nearly) dependent");
}
