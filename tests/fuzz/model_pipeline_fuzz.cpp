// libFuzzer target: model text -> parse -> every compiler pass -> compiled-model JSON, as
// `sidc compile` runs them, then that JSON read back as `sidc fit` reads a compiled model.
//
// Relies on: compiler/pipeline.hpp (compile, compiled_model, read_compiled_model). Guarantees:
// any bytes either compile or come back as diagnostics; a crash, a sanitizer report, a hang
// (-timeout) or a compiled model that its own reader refuses is a finding (the target aborts).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "compiler/pipeline.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto source = std::make_shared<const sidc::SourceFile>("fuzz.sid", std::string(reinterpret_cast<const char*>(data), size));
  sidc::CompileResult result = sidc::compile(source, {});
  (void)result.diagnostics.render_all();
  if (!result.ok()) return 0;
  const sidc::CompiledModel compiled = sidc::compiled_model(source, *result.normalized, *result.integrated);
  const std::string json = sidc::to_json(compiled).dump(1);
  // What the compiler writes, its reader must take back.
  std::string error;
  if (!sidc::read_compiled_model(nlohmann::ordered_json::parse(json), "fuzz.sidc.json", error)) {
    std::fprintf(stderr, "compiled model refused by its own reader: %s\n", error.c_str());
    std::abort();
  }
  return 0;
}
