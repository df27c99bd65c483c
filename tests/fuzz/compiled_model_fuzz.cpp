// libFuzzer target: the compiled-model reader (`sidc fit m.sidc.json`): bytes -> JSON ->
// read_compiled_model, which checks the file and derives the explicit form again.
//
// Relies on: compiler/pipeline.hpp (read_compiled_model), nlohmann-json's non-throwing parse,
// as compiler/load_model.cpp calls them. Guarantees: any bytes are either a compiled model or an
// error message; a crash, a sanitizer report or a hang (-timeout) is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "compiler/pipeline.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto j = nlohmann::ordered_json::parse(data, data + size, nullptr, false);
  if (j.is_discarded()) return 0;
  std::string error;
  (void)sidc::read_compiled_model(j, "fuzz.sidc.json", error);
  return 0;
}
