#include "cli/compile_command.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <fmt/format.h>
#include <iostream>

#include "cli/exit_codes.hpp"
#include "cli/form_options.hpp"
#include "cli/output_check.hpp"
#include "report/atomic_file.hpp"
#include "ir/compiled_model.hpp"
#include "compiler/pipeline.hpp"
#include "ir/print.hpp"
#include "grammar/ast_printer.hpp"
#include "diagnostics/cli_catalogue.hpp"
#include "diagnostics/model_catalogue.hpp"
#include "ir/settings.hpp"

namespace sidc {
namespace {

struct CompileArguments {
  std::string model;
  std::string output;
  FormArguments form_options;  // --integrate, --form (form_options.hpp)
  std::string dump;
  std::string dump_after;
};

std::vector<std::string> pass_names() {
  std::vector<std::string> names;
  for (const auto& p : passes()) names.emplace_back(p.name);
  return names;
}

// Which pass a --dump or --dump-after value names; nullopt after printing the diagnostic.
std::optional<std::string> pass_to_stop_after(const CompileArguments& a) {
  static const std::map<std::string, std::string> stages{{"ast", "parse"}, {"normalized", "normalize"}, {"integrated", "integrate"}};
  if (!a.dump.empty()) {
    if (auto it = stages.find(a.dump); it != stages.end()) return it->second;
    std::cerr << render(diag::unknown_pass(a.dump, diag::nearest(a.dump, {"ast", "normalized", "integrated"}), "ast, normalized, integrated")) << "\n";
    return std::nullopt;
  }
  const auto names = pass_names();
  if (std::find(names.begin(), names.end(), a.dump_after) != names.end()) return a.dump_after;
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  std::cerr << render(diag::unknown_pass(a.dump_after, diag::nearest(a.dump_after, names), list)) << "\n";
  return std::nullopt;
}

// A comment block heading the printed model: where it came from, and what integration added.
std::string summary(const ir::Model& m, const std::string& path) {
  std::string out = fmt::format("# {}: {} equation{}, {} parameter{}\n", path, m.equations.size(), m.equations.size() == 1 ? "" : "s",
                                m.parameters.size(), m.parameters.size() == 1 ? "" : "s");
  std::string implicit, constants;
  for (const auto& p : m.parameters) {
    if (p.origin == ir::Parameter::Origin::implicit) implicit += (implicit.empty() ? "" : ", ") + p.name;
    if (p.origin == ir::Parameter::Origin::integration_constant)
      constants += fmt::format("{}{} (equation {})", constants.empty() ? "" : ", ", p.name, p.equation + 1);
  }
  if (!implicit.empty()) out += "# no `param` declaration: parameters taken from the free names: " + implicit + "\n";
  for (std::size_t i = 0; i < m.equations.size(); ++i) {
    const int n = m.equations[i].integrations;
    if (n > 0) out += fmt::format("# equation {} integrated {} time{} from t0 to t\n", i + 1, n, n == 1 ? "" : "s");
  }
  if (!constants.empty()) out += "# integration constants: " + constants + "\n";
  std::string units, unitless;
  for (const auto& p : m.parameters) {
    if (p.unit) units += fmt::format("{}{} [{}]", units.empty() ? "" : ", ", p.name, to_string(*p.unit));
    else unitless += (unitless.empty() ? "" : ", ") + p.name;
  }
  if (!units.empty()) {
    out += "# parameter units (from the signals'): " + units + "\n";
    if (!unitless.empty()) out += "# no unit (a signal of its term, or its equation's known side, has none): " + unitless + "\n";
  }
  if (m.form_from_data)
    out += "# no form named: `sidc fit` chooses weak, derivative or integrated from the data (`set form` names one); printed: the derivative form\n";
  return out;
}

int run_compile(const CompileArguments& a) {
  if (const auto input = input_overwritten_by(a.output, {a.model}); !input.empty())
    return fail(render(cli_diag::output_is_input(a.output, input)), exit_code::usage_error);
  if (auto problem = output_problem("-o", a.output, OutputKind::file)) return fail(*problem, exit_code::user_error);
  auto text = read_text_file(a.model);
  if (auto* d = std::get_if<Diagnostic>(&text)) {
    std::cerr << render(cli_diag::model_not_read(*d)) << "\n";
    return exit_code::user_error;
  }
  CompileOptions options;
  std::string error;
  options.integrate.override_request = integration_request(a.form_options, error);
  if (!error.empty()) return fail(error, exit_code::usage_error);
  const bool dumping = !a.dump.empty() || !a.dump_after.empty();
  if (dumping) {
    auto stop = pass_to_stop_after(a);
    if (!stop) return exit_code::usage_error;
    options.stop_after = *stop;
  }
  auto source = std::make_shared<const SourceFile>(a.model, std::get<std::string>(std::move(text)));
  CompileResult r = compile(source, options);
  std::cerr << r.diagnostics.render_all();
  if (!r.ok()) return exit_code::user_error;

  if (dumping) {
    if (r.last_pass == "parse") std::cout << print_ast(r.parsed.model);
    else if (r.last_pass == "declare") std::cout << "# declarations checked; nothing is rewritten before `lower`\n";
    else if (r.last_pass == "lower") std::cout << r.lowered_text;
    else if (r.last_pass == "normalize" || r.last_pass == "units") std::cout << print(*r.normalized);
    else std::cout << print(*r.integrated);
    return exit_code::success;
  }

  std::cout << summary(*r.integrated, a.model) << print(*r.integrated);
  std::string output = a.output;
  if (output.empty()) output = std::filesystem::path(a.model).replace_extension(".sidc.json").string();
  // A data path is relative to the model file; the compiled model may be written elsewhere
  // (`-o`), and `sidc fit` reads paths relative to it: rebase them.
  ir::Model written = *r.integrated;
  const auto model_dir = std::filesystem::absolute(a.model).parent_path();
  const auto output_dir = std::filesystem::absolute(output).parent_path();
  for (auto& d : written.data)
    if (std::filesystem::path(d.path).is_relative())
      d.path = (model_dir / d.path).lexically_normal().lexically_relative(output_dir).string();
  const std::string json = to_json(CompiledModel{source, *r.normalized, written, std::nullopt}).dump(1) + "\n";
  if (std::string why; !write_file_atomically(output, json, &why)) {
    std::cerr << render(cli_diag::cannot_write(why, "choose a writable place with `-o FILE`")) << "\n";
    return exit_code::user_error;
  }
  std::cerr << "wrote " << output << "\n";
  return exit_code::success;
}

}  // namespace

void add_compile_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<CompileArguments>();
  CLI::App* cmd = app.add_subcommand("compile", "Check a model file, rewrite it into integrated form, and write the compiled model");
  cmd->add_option("model", args->model, "The model file (.sid)")->required();
  cmd->add_option("-o,--output", args->output, "Where to write the compiled model (default: MODEL with extension .sidc.json)");
  add_form_options(cmd, args->form_options);
  auto* dump = cmd->add_option("--dump", args->dump, "Print one stage instead of compiling: ast, normalized or integrated");
  cmd->add_option("--dump-after", args->dump_after, "Print the model after the named pass (parse, declare, lower, normalize, units, integrate, weak, hold)")
      ->excludes(dump);
  cmd->callback([args, &exit_status] { exit_status = run_compile(*args); });
}

}  // namespace sidc
