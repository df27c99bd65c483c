// `sidc export` (see export_command.hpp): parses the options, calls the library and prints.
//
// Relies on: fit.json's `model_source` (the model's text; report/fit_files.cpp), compiled here in
// memory as `sidc fit model.sid` compiles it, and its parameter values read as `sidc simulate
// --params` reads them (cli/fitted_values.hpp); report/model_export.hpp writes the text.
// Guarantees: the text on stdout, or written atomically to `-o FILE` (`wrote FILE` on stderr);
// every problem a message with exit code 1 (a file, the model) or 2 (the command line).
#include "cli/export_command.hpp"

#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli/exit_codes.hpp"
#include "cli/fitted_values.hpp"
#include "cli/output_check.hpp"
#include "compiler/explicit_form_pass.hpp"
#include "compiler/pipeline.hpp"
#include "diagnostics/cli_catalogue.hpp"
#include "report/atomic_file.hpp"
#include "report/model_export.hpp"

namespace sidc {
namespace {

struct ExportArguments {
  std::string fit;
  std::string language;
  std::string out;
};

int run_export(const ExportArguments& a) {
  if (auto problem = output_problem("-o", a.out, OutputKind::file)) return fail(*problem, exit_code::user_error);
  std::string error;
  auto text = read_whole_file(a.fit, error);
  if (!text) return fail(error, exit_code::user_error);
  const auto j = nlohmann::json::parse(*text, nullptr, false);
  const auto fitted = fitted_values(j);
  if (!fitted) return fail(render(cli_diag::not_a_fit_file(a.fit)), exit_code::user_error);
  if (!j.contains("model_source") || !j["model_source"].is_string()) return fail(render(cli_diag::fit_file_without_model(a.fit)), exit_code::user_error);

  // The model as it was fitted, compiled in memory; its diagnostics name fit.json's model.
  const std::string model_name = j.value("compiled_model", a.fit);
  auto source = std::make_shared<const SourceFile>(model_name, j["model_source"].get<std::string>());
  CompileResult compiled = compile(source, {});
  if (!compiled.ok()) return fail(compiled.diagnostics.render_all(), exit_code::user_error);
  const ir::Model& as_compiled = *compiled.normalized;

  std::vector<std::optional<double>> values(as_compiled.parameters.size());
  for (const auto& [name, value] : *fitted)
    if (const int index = as_compiled.parameter_index(name); index >= 0) values[static_cast<std::size_t>(index)] = value;  // integration constants: not in the derivative form
  std::string missing;
  std::vector<double> all;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!values[i]) missing += (missing.empty() ? "`" : ", `") + as_compiled.parameters[i].name + "`";
    all.push_back(values[i].value_or(0.0));
  }
  if (!missing.empty()) return fail(render(cli_diag::cannot_export("fit.json gives no finite estimate of " + missing)), exit_code::user_error);
  // Nonlinear parameters (`sin(L*theta)`) are declared with the others and named where they stand.
  const ir::Model& model = as_compiled;
  const std::vector<double>& known = all;

  const std::map<std::string, ExportLanguage> languages{{"c", ExportLanguage::c}, {"python", ExportLanguage::python}, {"latex", ExportLanguage::latex}};
  const ExportLanguage language = languages.at(a.language);
  auto form = explicit_form(model);
  const ExplicitForm none;
  if (auto* d = std::get_if<Diagnostic>(&form); d && language != ExportLanguage::latex)
    return fail(render(cli_diag::cannot_export("the equations cannot be solved for their highest derivatives: " + d->message)), exit_code::user_error);
  const ExplicitForm& explicit_ = std::holds_alternative<ExplicitForm>(form) ? std::get<ExplicitForm>(form) : none;
  auto written = export_model({model, explicit_, known, "`" + a.fit + "`"}, language);
  if (auto* d = std::get_if<Diagnostic>(&written)) return fail(render(*d), exit_code::user_error);
  const std::string& output = std::get<std::string>(written);
  if (a.out.empty()) {
    std::cout << output;
    return exit_code::success;
  }
  if (std::string why; !write_file_atomically(a.out, output, &why)) return fail(render(cli_diag::cannot_write(why)), exit_code::user_error);
  std::cerr << "wrote " << a.out << "\n";
  return exit_code::success;
}

}  // namespace

void add_export_command(CLI::App& app, int& exit_status) {
  auto a = std::make_shared<ExportArguments>();
  CLI::App* cmd = app.add_subcommand("export", "Write the fitted equations with their numbers: C or Python right-hand side, or LaTeX");
  cmd->add_option("fit", a->fit, "The fit.json of `sidc fit --out DIR`")->required();
  cmd->add_option("--as", a->language, "c or python (a right-hand-side function: state in, derivatives out), or latex (the equations and a table)")
      ->required()
      ->check(CLI::IsMember({"c", "python", "latex"}));
  cmd->add_option("-o,--out", a->out, "Write to this file (default: stdout)");
  cmd->callback([a, &exit_status] { exit_status = run_export(*a); });
}

}  // namespace sidc
