// The compiler's passes in order, and `compile`, which runs them.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "compiler/integrate_pass.hpp"
#include "ir/compiled_model.hpp"
#include "ir/ir.hpp"
#include "grammar/parse.hpp"

namespace sidc {

struct PassInfo {
  const char* name;
  const char* reason;  // why it stands where it does
};
// parse, declare, lower, normalize, integrate, weak: see pipeline.cpp.
const std::vector<PassInfo>& passes();

struct CompileOptions {
  IntegrateOptions integrate;
  std::string stop_after;  // a pass name: stop there (for --dump-after); empty = run them all
};

struct CompileResult {
  ParseResult parsed;
  std::optional<ir::Model> normalized;  // after normalize_pass
  std::optional<ir::Model> integrated;  // after integrate_pass and weak_pass: what `sidc fit` solves
  std::string last_pass;                // the last pass that ran
  Diagnostics diagnostics;
  std::string lowered_text;             // lower_pass's equations, printed, for --dump-after=lower
  bool ok() const { return !diagnostics.has_errors(); }
};

CompileResult compile(std::shared_ptr<const SourceFile> source, const CompileOptions& options);

// The compiled model of a successful compile, carrying the explicit form of `normalized`
// (explicit_form_pass), derived once here for every command that solves the equations.
CompiledModel compiled_model(std::shared_ptr<const SourceFile> source, const ir::Model& normalized, const ir::Model& integrated);

// The equations of `normalized` rewritten into `form` (`derivative`, `integrated` or `weak`), as
// `sidc compile --form` rewrites them: the candidates of sidc fit's choice of form when the model
// names none (runtime/simulate/form_choice.hpp).
ir::Model rewritten_in_form(const ir::Model& normalized, const std::string& form);

// A compiled model file read back (ir/compiled_model.hpp), its explicit form derived again (the file
// does not hold it); nullopt with `error` naming what is wrong.
std::optional<CompiledModel> read_compiled_model(const nlohmann::ordered_json& j, const std::string& path, std::string& error);

}  // namespace sidc
