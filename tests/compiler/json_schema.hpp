// Test support: a small JSON Schema validator, enough for docs/compiled-model.schema.json.
//
// Relies on nlohmann::json. Implements the subset of JSON Schema (draft 2020-12) that the schema
// uses, with the standard's meaning: type (a name or an array of names, so `["number", "null"]`
// is a nullable number), enum, const, required, properties, additionalProperties (false or a
// schema), items (one schema for every element), minItems, minLength, pattern (ECMAScript,
// searched, as the standard says), minimum, maximum, exclusiveMinimum, $ref (only `#/$defs/NAME`,
// applied alongside the other keywords of its schema), oneOf and anyOf. Annotations ($schema,
// $id, $comment, title, description, $defs) are skipped.
//
// Guarantees: a keyword outside this subset is reported by `unsupported_keywords`, so that a
// schema cannot silently rely on something this validator ignores; `validate_against_schema`
// (given a schema that passes that check and whose keyword values have their standard types)
// returns every problem, each named by the JSON Pointer of the offending value
// (`/equations/0/known/terms/1/coefficient: ...`), and never throws.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace sidc::testing {

// Keywords of `schema` (and of every schema inside it) that the validator does not implement,
// each with the JSON Pointer of the schema that holds it. Empty when the schema is usable.
std::vector<std::string> unsupported_keywords(const nlohmann::json& schema);

// Every way `document` violates `schema`; empty when it is valid.
std::vector<std::string> validate_against_schema(const nlohmann::json& schema, const nlohmann::json& document);

}  // namespace sidc::testing
