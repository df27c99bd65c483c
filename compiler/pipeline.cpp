// The table of contents of the compiler: each pass, in order, with the reason for its place.
// docs/architecture.md maps each to its file and to the flag that prints its result
// (`sidc compile --dump-after=PASS`).
#include "compiler/pipeline.hpp"

#include <algorithm>

#include "compiler/declare_pass.hpp"
#include "compiler/explicit_form_pass.hpp"
#include "compiler/hold_check_pass.hpp"
#include "compiler/lower_pass.hpp"
#include "compiler/normalize_pass.hpp"
#include "compiler/unit_pass.hpp"
#include "compiler/weak_pass.hpp"
#include "ir/print.hpp"
#include "ir/queries.hpp"
#include "ir/settings.hpp"

namespace sidc {

namespace {

// The integration constants a form pass adds get their units the same way; everything else was
// checked on the linear form, so nothing is reported here.
void units_of_new_parameters(ir::Model& m) {
  Diagnostics ignored;
  unit_pass(m, ignored);
}

}  // namespace

const std::vector<PassInfo>& passes() {
  static const std::vector<PassInfo> list{
      {"parse", "text to AST; first, as everything else reads the tree (grammar/parse.cpp)"},
      {"declare", "names, families, settings and data bindings; before lowering, which resolves names against them"},
      {"lower", "expressions to canonical sums; needs every name declared, and gives normalize plain factors"},
      {"normalize", "the thesis' linear form sum a_k op_k = known; needs canonical sums to find like terms"},
      {"units", "each parameter's unit from its operation and the known side; on the linear form, where each parameter has one operation"},
      {"integrate", "integrated form (sections 2-1, 2-2); works on the linear form, one operation at a time"},
      {"weak", "weak form for the equations that ask for it; after integrate, which leaves them alone, and like it on the linear form"},
      {"hold", "no derivative of a held or linear input is left; after the form passes, which integrate such derivatives away"},
  };
  return list;
}

CompileResult compile(std::shared_ptr<const SourceFile> source, const CompileOptions& options) {
  CompileResult r;
  auto stop = [&](const char* pass) {
    r.last_pass = pass;
    return options.stop_after == pass || r.diagnostics.has_errors();
  };
  r.parsed = parse_model(std::move(source));
  r.diagnostics = r.parsed.diagnostics;
  if (stop("parse")) return r;
  Declarations declarations = declare_pass(r.parsed, r.diagnostics);
  if (stop("declare")) return r;
  LoweredModel lowered = lower_pass(std::move(declarations), r.parsed, r.diagnostics);
  for (const auto& e : lowered.equations) r.lowered_text += print(e.lhs) + " = " + print(e.rhs) + "\n";
  // Errors in some equations still let the others be normalized, for a fuller report in one run.
  r.last_pass = "lower";
  if (options.stop_after == "lower") return r;
  r.normalized = normalize_pass(std::move(lowered), r.diagnostics);
  if (stop("normalize")) return r;
  unit_pass(*r.normalized, r.diagnostics);
  if (stop("units")) return r;
  r.integrated = integrate_pass(*r.normalized, options.integrate, r.diagnostics);
  if (stop("integrate")) return r;
  r.integrated = weak_pass(std::move(*r.integrated), r.diagnostics);
  units_of_new_parameters(*r.integrated);
  // Nothing names a form (`set constants` alone does not): the fit chooses it from the data.
  const bool named = options.integrate.override_request ||
                     std::any_of(r.normalized->equations.begin(), r.normalized->equations.end(),
                                 [](const ir::Equation& e) { return e.integration.span.known(); });
  r.integrated->form_from_data = !named && !is_static(*r.integrated);
  if (stop("weak")) return r;
  // A model whose form the fit chooses is checked in each candidate form there (fit_command.cpp).
  if (!r.integrated->form_from_data) hold_check_pass(*r.integrated, r.diagnostics);
  stop("hold");
  return r;
}

// After the passes: the explicit form (explicit_form_pass.cpp) works on the normalized model, before
// integration, and its failure is no compile error: a model that cannot be solved can still be fitted.
CompiledModel compiled_model(std::shared_ptr<const SourceFile> source, const ir::Model& normalized, const ir::Model& integrated) {
  return CompiledModel{std::move(source), normalized, integrated, explicit_form(normalized)};
}

ir::Model rewritten_in_form(const ir::Model& normalized, const std::string& form) {
  IntegrateOptions options;
  ir::IntegrationRequest request;
  request_form(request, form);
  options.override_request = request;
  // The model compiled without a request; integrate and weak add no error to a dynamic model's
  // normalized form (form_from_data is set only for those).
  Diagnostics ignored;
  ir::Model m = weak_pass(integrate_pass(normalized, options, ignored), ignored);
  m.form_from_data = false;
  units_of_new_parameters(m);
  return m;
}

std::optional<CompiledModel> read_compiled_model(const nlohmann::ordered_json& j, const std::string& path, std::string& error) {
  auto compiled = compiled_model_from_json(j, path, error);
  if (!compiled) return compiled;
  compiled->explicit_form = explicit_form(compiled->normalized);
  // The file holds the signals' units; the parameters' follow from them as at compile time.
  units_of_new_parameters(compiled->normalized);
  units_of_new_parameters(compiled->integrated);
  return compiled;
}

}  // namespace sidc
