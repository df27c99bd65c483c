// Test support: compile model text held in a string.
#pragma once

#include <string>

#include "compiler/pipeline.hpp"

namespace sidc::testing {

inline CompileResult compile_text(const std::string& text, CompileOptions options = {}) {
  return compile(std::make_shared<const SourceFile>("test.sid", text), options);
}

}  // namespace sidc::testing
