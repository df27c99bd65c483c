#include "compiler/load_model.hpp"

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <string_view>

#include "compiler/pipeline.hpp"
#include "diagnostics/cli_catalogue.hpp"

namespace sidc {
namespace fs = std::filesystem;
namespace {

// How deep a compiled model's JSON may nest: the root, its equations, an operation (6 levels),
// then 6 levels for each of the reader's kMaxCompiledNesting levels of functions, powers, der(),
// int() and guards (ir/compiled_model.cpp), with room to spare. The JSON library copies an
// object's members when it adds one after a nested value, so a file nested 25 000 deep took
// minutes to parse; counted here first, in one pass over the text, it is refused at once.
constexpr std::size_t kMaxJsonDepth = 2000;

// The deepest nesting of `[` and `{` outside strings.
std::size_t json_depth(std::string_view text) {
  std::size_t depth = 0, deepest = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
      if (deepest > kMaxJsonDepth) return deepest;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return deepest;
}

}  // namespace

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
  if (json_depth(*text) > kMaxJsonDepth) {
    error = render(cli_diag::invalid_compiled_model(path, fmt::format("its JSON is nested more than {} levels deep", kMaxJsonDepth)));
    return std::nullopt;
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
