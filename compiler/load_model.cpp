#include "compiler/load_model.hpp"

#include <filesystem>

#include "compiler/pipeline.hpp"
#include "diagnostics/cli_catalogue.hpp"

namespace sidc {
namespace fs = std::filesystem;

std::optional<CompiledModel> load_compiled_model(const std::string& path, std::string& error, std::string& warnings) {
  auto text = read_whole_file(path, error);
  if (!text) return std::nullopt;
  if (path.ends_with(".sid")) {
    auto source = std::make_shared<const SourceFile>(path, std::move(*text));
    CompileResult r = compile(source, {});
    if (!r.ok()) {
      error = r.diagnostics.render_all();
      if (!error.empty() && error.back() == '\n') error.pop_back();
      return std::nullopt;
    }
    warnings += r.diagnostics.render_all();
    return compiled_model(source, *r.normalized, *r.integrated);
  }
  const nlohmann::ordered_json j = nlohmann::ordered_json::parse(*text, nullptr, false);
  if (j.is_discarded()) {
    error = render(cli_diag::compiled_model_not_json(path));
    return std::nullopt;
  }
  auto compiled = read_compiled_model(j, path, error);
  if (!compiled) return std::nullopt;
  // A model file changed since it was compiled makes a stale fit: say so.
  const fs::path source = fs::path(path).parent_path() / fs::path(compiled->source->name).filename();
  std::string ignored;
  if (auto now = read_whole_file(source.string(), ignored); now && source_hash(*now) != source_hash(compiled->source->text))
    warnings += render(cli_diag::model_changed_since_compiled(source.string(), path)) + "\n";
  return compiled;
}

}  // namespace sidc
