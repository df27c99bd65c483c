#include "json_schema.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <regex>
#include <set>

namespace sidc::testing {
namespace {

using nlohmann::json;

const std::set<std::string>& annotations() {
  static const std::set<std::string> names{"$schema", "$id", "$comment", "title", "description", "$defs"};
  return names;
}

const std::set<std::string>& implemented() {
  static const std::set<std::string> names{"type",    "enum",    "const",   "required", "properties",       "additionalProperties",
                                           "items",   "minItems", "minLength", "pattern", "minimum", "maximum",
                                           "exclusiveMinimum", "$ref", "oneOf", "anyOf"};
  return names;
}

// JSON Pointer escaping of one key (RFC 6901): `~` -> `~0`, `/` -> `~1`.
std::string pointer_step(const std::string& key) {
  std::string out;
  for (char c : key) out += c == '~' ? "~0" : c == '/' ? "~1" : std::string(1, c);
  return "/" + out;
}

std::string shown(const std::string& pointer) { return pointer.empty() ? "(root)" : pointer; }

bool has_type(const json& value, const std::string& type) {
  if (type == "null") return value.is_null();
  if (type == "boolean") return value.is_boolean();
  if (type == "object") return value.is_object();
  if (type == "array") return value.is_array();
  if (type == "string") return value.is_string();
  if (type == "number") return value.is_number();
  // The standard counts 2.0 as an integer too.
  if (type == "integer")
    return value.is_number_integer() || (value.is_number_float() && std::trunc(value.get<double>()) == value.get<double>());
  return false;
}

// Code points, as minLength counts them: every byte that does not continue a UTF-8 sequence.
std::size_t code_points(const std::string& s) {
  return static_cast<std::size_t>(std::count_if(s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

class Validator {
 public:
  explicit Validator(const json& root) : root_(root) {}

  void check(const json& schema, const json& value, const std::string& at, std::vector<std::string>& errors) const {
    if (schema.is_boolean()) {
      if (!schema.get<bool>()) errors.push_back(shown(at) + ": no value is allowed here");
      return;
    }
    if (auto ref = schema.find("$ref"); ref != schema.end()) {
      const json* target = resolve(*ref);
      if (!target) errors.push_back(shown(at) + ": the schema's $ref " + ref->dump() + " names no entry of $defs");
      else check(*target, value, at, errors);
    }
    if (auto type = schema.find("type"); type != schema.end() && !type_allows(*type, value)) {
      errors.push_back(type_mismatch(*type, value, at));
      return;  // the other keywords would only repeat the mismatch
    }
    if (auto c = schema.find("const"); c != schema.end() && value != *c)
      errors.push_back(shown(at) + ": expected " + c->dump() + ", found " + brief(value));
    if (auto e = schema.find("enum"); e != schema.end() && std::find(e->begin(), e->end(), value) == e->end())
      errors.push_back(shown(at) + ": expected one of " + e->dump() + ", found " + brief(value));
    if (value.is_number()) check_bounds(schema, value, at, errors);
    if (value.is_string()) check_string(schema, value.get<std::string>(), at, errors);
    if (value.is_object()) check_object(schema, value, at, errors);
    if (value.is_array()) check_array(schema, value, at, errors);
    if (auto any = schema.find("anyOf"); any != schema.end()) check_alternatives(*any, value, at, false, errors);
    if (auto one = schema.find("oneOf"); one != schema.end()) check_alternatives(*one, value, at, true, errors);
  }

 private:
  const json& root_;
  mutable std::map<std::string, std::regex> patterns_;  // compiled once per validation

  const json* resolve(const json& ref) const {
    static const std::string prefix = "#/$defs/";
    if (!ref.is_string() || ref.get<std::string>().rfind(prefix, 0) != 0) return nullptr;
    const auto defs = root_.find("$defs");
    if (defs == root_.end()) return nullptr;
    const auto target = defs->find(ref.get<std::string>().substr(prefix.size()));
    return target == defs->end() ? nullptr : &*target;
  }

  // `type` is one name or an array of names.
  static bool type_allows(const json& type, const json& value) {
    if (type.is_string()) return has_type(value, type.get<std::string>());
    return std::any_of(type.begin(), type.end(), [&](const json& t) { return has_type(value, t.get<std::string>()); });
  }

  static std::string type_mismatch(const json& type, const json& value, const std::string& at) {
    return shown(at) + ": expected " + type.dump() + ", found " + std::string(value.type_name()) + " " + brief(value);
  }

  static std::string brief(const json& value) {
    std::string text = value.dump();
    return text.size() > 60 ? text.substr(0, 57) + "..." : text;
  }

  static void check_bounds(const json& schema, const json& value, const std::string& at, std::vector<std::string>& errors) {
    const double v = value.get<double>();
    if (auto m = schema.find("minimum"); m != schema.end() && v < m->get<double>())
      errors.push_back(shown(at) + ": " + value.dump() + " is below the minimum " + m->dump());
    if (auto m = schema.find("maximum"); m != schema.end() && v > m->get<double>())
      errors.push_back(shown(at) + ": " + value.dump() + " is above the maximum " + m->dump());
    if (auto m = schema.find("exclusiveMinimum"); m != schema.end() && v <= m->get<double>())
      errors.push_back(shown(at) + ": " + value.dump() + " is not above " + m->dump());
  }

  void check_string(const json& schema, const std::string& s, const std::string& at, std::vector<std::string>& errors) const {
    if (auto m = schema.find("minLength"); m != schema.end() && code_points(s) < m->get<std::size_t>())
      errors.push_back(shown(at) + ": shorter than " + m->dump() + " characters");
    if (auto p = schema.find("pattern"); p != schema.end()) {
      auto compiled = patterns_.find(p->get<std::string>());
      if (compiled == patterns_.end()) compiled = patterns_.emplace(p->get<std::string>(), std::regex(p->get<std::string>())).first;
      if (!std::regex_search(s, compiled->second)) errors.push_back(shown(at) + ": " + brief(s) + " does not match the pattern " + p->dump());
    }
  }

  void check_object(const json& schema, const json& object, const std::string& at, std::vector<std::string>& errors) const {
    if (auto required = schema.find("required"); required != schema.end())
      for (const auto& name : *required)
        if (!object.contains(name.get<std::string>())) errors.push_back(shown(at) + ": the required property " + name.dump() + " is missing");
    const auto properties = schema.find("properties");
    const auto additional = schema.find("additionalProperties");
    for (const auto& [key, value] : object.items()) {
      const std::string where = at + pointer_step(key);
      if (properties != schema.end() && properties->contains(key)) check(properties->at(key), value, where, errors);
      else if (additional != schema.end()) {
        if (additional->is_boolean() && !additional->get<bool>()) errors.push_back(shown(at) + ": unexpected property \"" + key + "\"");
        else check(*additional, value, where, errors);
      }
    }
  }

  void check_array(const json& schema, const json& array, const std::string& at, std::vector<std::string>& errors) const {
    if (auto m = schema.find("minItems"); m != schema.end() && array.size() < m->get<std::size_t>())
      errors.push_back(shown(at) + ": fewer than " + m->dump() + " items");
    if (auto items = schema.find("items"); items != schema.end())
      for (std::size_t i = 0; i < array.size(); ++i) check(*items, array[i], at + "/" + std::to_string(i), errors);
  }

  // Why `value` certainly fails `schema` at first sight: its type is not allowed, or a member that
  // the schema fixes with `const` (a union's tag, such as a factor's `kind`) has another value.
  // Looks through $ref. Empty when a full check is needed.
  std::string plain_mismatch(const json& schema, const json& value, const std::string& at) const {
    if (!schema.is_object()) return {};
    if (auto ref = schema.find("$ref"); ref != schema.end())
      if (const json* target = resolve(*ref))
        if (auto why = plain_mismatch(*target, value, at); !why.empty()) return why;
    if (auto type = schema.find("type"); type != schema.end() && !type_allows(*type, value)) return type_mismatch(*type, value, at);
    if (auto properties = schema.find("properties"); properties != schema.end() && value.is_object())
      for (const auto& [key, sub] : properties->items())
        if (sub.is_object() && sub.contains("const") && value.contains(key) && value.at(key) != sub.at("const"))
          return shown(at + pointer_step(key)) + ": expected " + sub.at("const").dump() + ", found " + brief(value.at(key));
    return {};
  }

  // anyOf: at least one alternative holds; oneOf: exactly one. Alternatives that fail at first
  // sight (plain_mismatch) are not checked further, which keeps nested unions (a factor holds
  // sums of factors) linear in the document's size. On failure the problems of the nearest
  // alternative are shown: among those checked in full, the one with the fewest problems, which
  // for a union told apart by a `const` tag is the one whose tag the value carries.
  void check_alternatives(const json& alternatives, const json& value, const std::string& at, bool exactly_one,
                          std::vector<std::string>& errors) const {
    std::vector<std::size_t> holding;
    std::vector<std::string> nearest;
    bool checked_any = false;
    for (std::size_t i = 0; i < alternatives.size(); ++i) {
      if (std::string why = plain_mismatch(alternatives[i], value, at); !why.empty()) {
        if (!checked_any && nearest.empty()) nearest = {why};
        continue;
      }
      std::vector<std::string> problems;
      check(alternatives[i], value, at, problems);
      if (problems.empty()) holding.push_back(i);
      else if (!checked_any || problems.size() < nearest.size()) nearest = std::move(problems);
      checked_any = true;
    }
    const char* keyword = exactly_one ? "oneOf" : "anyOf";
    if (holding.empty()) {
      std::string message = shown(at) + ": matches none of the " + std::to_string(alternatives.size()) + " alternatives of " + keyword +
                            (checked_any ? "; the nearest fails with:" : "; the first fails with:");
      for (const auto& p : nearest) message += "\n    " + p;
      errors.push_back(message);
    } else if (exactly_one && holding.size() > 1) {
      errors.push_back(shown(at) + ": matches alternatives " + std::to_string(holding[0]) + " and " + std::to_string(holding[1]) +
                       " of oneOf, exactly one expected");
    }
  }
};

void collect_unsupported(const json& schema, const json& root, const std::string& at, std::vector<std::string>& out) {
  if (schema.is_boolean()) return;
  if (!schema.is_object()) {
    out.push_back(shown(at) + ": a schema must be an object or a boolean");
    return;
  }
  for (const auto& [key, value] : schema.items()) {
    const std::string where = at + pointer_step(key);
    if (key == "$defs" || key == "properties") {
      for (const auto& [name, sub] : value.items()) collect_unsupported(sub, root, where + pointer_step(name), out);
    } else if (key == "additionalProperties" || key == "items") {
      collect_unsupported(value, root, where, out);
    } else if (key == "oneOf" || key == "anyOf") {
      for (std::size_t i = 0; i < value.size(); ++i) collect_unsupported(value[i], root, where + "/" + std::to_string(i), out);
    } else if (key == "$ref") {
      const std::string ref = value.is_string() ? value.get<std::string>() : std::string();
      const std::string name = ref.rfind("#/$defs/", 0) == 0 ? ref.substr(8) : std::string();
      if (name.empty() || !root.contains("$defs") || !root.at("$defs").contains(name))
        out.push_back(shown(at) + ": $ref " + value.dump() + " is not of the form #/$defs/NAME with NAME defined");
    } else if (key == "pattern") {
      try {
        std::regex check(value.get<std::string>());
      } catch (const std::exception&) {
        out.push_back(shown(where) + ": not a valid regular expression");
      }
    } else if (!implemented().count(key) && !annotations().count(key)) {
      out.push_back(shown(at) + ": keyword \"" + key + "\" is not implemented by this validator");
    }
  }
}

}  // namespace

std::vector<std::string> unsupported_keywords(const nlohmann::json& schema) {
  std::vector<std::string> out;
  collect_unsupported(schema, schema, "", out);
  return out;
}

std::vector<std::string> validate_against_schema(const nlohmann::json& schema, const nlohmann::json& document) {
  std::vector<std::string> errors;
  Validator(schema).check(schema, document, "", errors);
  return errors;
}

}  // namespace sidc::testing
