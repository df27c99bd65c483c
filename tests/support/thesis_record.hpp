// What the runtime tests that fit the thesis' section 4-1 record share: a model compiled from text
// (its diagnostics in the failure when it does not compile) and Appendix A's record bound to it.
// Header-only; the including test links sidc_compiler and sidc_runtime and defines SIDC_SOURCE_DIR.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <variant>

#include "compiler/pipeline.hpp"
#include "runtime/records/bind_record.hpp"
#include "runtime/records/records.hpp"

namespace sidc::testing {

// The integrated (rewritten) model of `text`; an empty model, and a test failure, when it does not compile.
inline ir::Model compiled_text(const std::string& name, const std::string& text) {
  const auto r = compile(std::make_shared<const SourceFile>(name, text), {});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return r.ok() ? *r.integrated : ir::Model{};
}

// examples/thesis-4-1/appendix_a.csv (t, y) bound to `model`, every `every`-th sample.
inline SampledRecord appendix_a(const ir::Model& model, int every = 1) {
  auto record = read_csv(SIDC_SOURCE_DIR "/examples/thesis-4-1/appendix_a.csv");
  EXPECT_TRUE(std::holds_alternative<Record>(record));
  ir::DataSource source;
  source.bindings = {{"t", "t"}, {"y", "y"}};
  BindOptions bind;
  bind.every = every;
  auto bound = bind_record(std::get<Record>(record), source, model, bind);
  EXPECT_TRUE(std::holds_alternative<SampledRecord>(bound)) << render(std::get<Diagnostic>(bound));
  return std::get<SampledRecord>(std::move(bound));
}

}  // namespace sidc::testing
