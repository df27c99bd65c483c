// The compiled model file (`model.sidc.json`): everything `sidc fit` needs, and nothing it must
// parse. Format documented in docs/compiled-model.md, with its JSON Schema in
// docs/compiled-model.schema.json; `version` changes whenever a reader would misread the file.
//
// Holds the signals, parameters (integration constants included), every equation both before and
// after integration as canonical text and as trees, with source spans, the typed settings, the
// data binding, and the source itself with its hash (so a reader can show the offending line, and
// tell when the model file changed since it was compiled). Writing is deterministic: compiling the
// same model twice gives byte-identical files.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <variant>

#include "diagnostics/diagnostic.hpp"
#include "ir/explicit_form.hpp"
#include "ir/ir.hpp"

namespace sidc {

inline constexpr int kCompiledModelVersion = 2;
// The highest derivative order a compiled model's test function may carry: a file asking for more
// is refused (its quadrature weights, scaled by h^-k, would overflow long before).
inline constexpr int kMaxWeakOrder = 16;

struct CompiledModel {
  std::shared_ptr<const SourceFile> source;
  ir::Model normalized;  // the derivative form (eq. 2-1.2): what `sidc simulate` solves
  ir::Model integrated;  // what is fitted
  // The normalized equations solved for each output's highest derivative, or why they cannot be
  // (compiler/explicit_form_pass): what `sidc simulate` and every validation solve. Derived by the
  // compiler (compiler/pipeline.hpp: compiled_model, read_compiled_model), never written to the
  // file; nullopt only in a CompiledModel put together by hand.
  std::optional<std::variant<ExplicitForm, Diagnostic>> explicit_form;
};

nlohmann::ordered_json to_json(const CompiledModel& compiled);

// Reads a compiled model back; nullopt with `error` naming what is wrong (`path` is for messages).
std::optional<CompiledModel> compiled_model_from_json(const nlohmann::ordered_json& j, const std::string& path, std::string& error);

// FNV-1a, 64 bits, as 16 hex digits: identifies the source text (not a security hash).
std::string source_hash(const std::string& text);

}  // namespace sidc
