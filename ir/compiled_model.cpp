#include "ir/compiled_model.hpp"

#include <algorithm>
#include <fmt/format.h>
#include <map>
#include <set>
#include <unordered_map>
#include <utility>

#include "diagnostics/cli_catalogue.hpp"
#include "ir/print.hpp"
#include "ir/traversal.hpp"
#include "ir/settings.hpp"

namespace sidc {
namespace {

using json = nlohmann::ordered_json;
using ordered = nlohmann::ordered_json;
using ir::FactorKind;

const char* kind_name(FactorKind k) {
  switch (k) {
    case FactorKind::parameter: return "parameter";
    case FactorKind::signal: return "signal";
    case FactorKind::time: return "time";
    case FactorKind::elapsed: return "elapsed";
    case FactorKind::window_start: return "window_start";
    case FactorKind::initial_value: return "initial_value";
    case FactorKind::function: return "function";
    case FactorKind::power: return "power";
    case FactorKind::derivative: return "derivative";
    case FactorKind::integral: return "integral";
    case FactorKind::guard: return "guard";
    case FactorKind::test_function: return "test_function";
  }
  return "?";
}

std::optional<FactorKind> kind_from(const std::string& s) {
  for (int k = 0; k <= static_cast<int>(FactorKind::guard); ++k)
    if (s == kind_name(static_cast<FactorKind>(k))) return static_cast<FactorKind>(k);
  return std::nullopt;
}

// A damaged file may hold 1e83 or 2^40 where a small integer belongs: converting it would be
// undefined behaviour (the fuzzer found one), so every integer is checked before it is read.
template <class T>
T integer(const json& j, const char* key) {
  const json& v = j.at(key);
  if (v.is_number_unsigned() && std::in_range<T>(v.get<std::uint64_t>())) return static_cast<T>(v.get<std::uint64_t>());
  if (v.is_number_integer() && !v.is_number_unsigned() && std::in_range<T>(v.get<std::int64_t>()))
    return static_cast<T>(v.get<std::int64_t>());
  throw std::runtime_error(fmt::format("`{}` is {}, not an integer that fits", key, v.dump()));
}

ordered number_json(const Number& n) {
  if (n.exact()) return ordered{{"num", n.numerator()}, {"den", n.denominator()}};
  return ordered{{"real", n.value()}};
}

ordered span_json(const Span& s) {
  if (!s.known()) return nullptr;
  const auto p = s.start();
  return ordered{{"line", p.line}, {"column", p.column}, {"length", s.length()}, {"offset", s.begin}};
}

ordered sum_json(const ir::Sum& s);

ordered factor_json(const ir::Factor& f, int power) {
  ordered j{{"kind", kind_name(f.kind)}};
  switch (f.kind) {
    case FactorKind::parameter: j["name"] = f.name; break;
    case FactorKind::signal: j["name"] = f.name, j["order"] = f.order; break;
    case FactorKind::initial_value:
      j["name"] = f.name, j["order"] = f.order;
      j["at"] = f.at ? number_json(*f.at) : ordered(nullptr);
      break;
    case FactorKind::function: j["name"] = f.name, j["argument"] = sum_json(*f.argument); break;
    case FactorKind::power: j["exponent"] = number_json(f.exponent), j["argument"] = sum_json(*f.argument); break;
    case FactorKind::derivative: j["order"] = f.order, j["argument"] = sum_json(*f.argument); break;
    case FactorKind::integral: j["argument"] = sum_json(*f.argument); break;
    case FactorKind::guard: {
      ordered conditions = ordered::array();
      for (const auto& c : f.conditions)
        conditions.push_back(ordered{{"lhs", sum_json(*c.lhs)}, {"relation", ir::to_string(c.relation)}, {"rhs", sum_json(*c.rhs)}});
      j["conditions"] = std::move(conditions);
      break;
    }
    case FactorKind::test_function: j["order"] = f.order; break;
    case FactorKind::time:
    case FactorKind::elapsed:
    case FactorKind::window_start: break;  // the kind says it all
  }
  j["power"] = power;
  return j;
}

ordered sum_json(const ir::Sum& s) {
  ordered terms = ordered::array();
  for (const auto& t : s.terms) {
    ordered factors = ordered::array();
    for (const auto& [f, power] : t.factors) factors.push_back(factor_json(f, power));
    terms.push_back(ordered{{"coefficient", number_json(t.coefficient)}, {"factors", std::move(factors)}, {"span", span_json(t.span)}});
  }
  return ordered{{"text", print(s)}, {"terms", std::move(terms)}};
}

ordered optional_number(const std::optional<double>& v) { return v ? ordered(*v) : ordered(nullptr); }

ordered settings_json(const ir::Settings& raw) {
  const EvaluationSettings e = evaluation_settings(raw);
  ordered j;
  if (e.derivative.automatic)  // chosen per signal and order from each record when fitting
    j["derivative"] = {{"method", "savitzky_golay"}, {"window", "auto"}, {"order", "auto"}};
  else
    j["derivative"] = {{"method", "savitzky_golay"}, {"window", e.derivative.window}, {"order", e.derivative.order}};
  j["second_derivative"] = e.second_derivative_repeated ? "repeated" : "direct";
  j["edges"] = e.shorten_edges ? "shorten" : "drop";
  j["integration"] = e.trapezoid ? "trapezoid" : "simpson";
  j["smooth_before_integration"] =
      e.smooth_before_integration ? ordered{{"window", e.smooth_before_integration->window}, {"order", e.smooth_before_integration->order}}
                                  : ordered(nullptr);
  j["from"] = optional_number(e.from);
  j["to"] = optional_number(e.to);
  j["every"] = e.every;
  j["step"] = optional_number(e.step);
  j["weights"] = e.weights ? ordered(*e.weights) : ordered(nullptr);
  ordered as_written = ordered::object();
  for (const auto& [key, value] : raw.values) as_written[key] = value.text;
  j["as_written"] = std::move(as_written);
  return j;
}

const char* origin_name(ir::Parameter::Origin o) {
  switch (o) {
    case ir::Parameter::Origin::declared: return "declared";
    case ir::Parameter::Origin::implicit: return "implicit";
    case ir::Parameter::Origin::integration_constant: return "integration_constant";
  }
  return "declared";
}

// ---- reading ------------------------------------------------------------------------------------

// One of `allowed`, or an error naming the field.
std::string one_of(const json& j, const char* field, std::initializer_list<const char*> allowed) {
  const std::string value = j.at(field).get<std::string>();
  for (const char* a : allowed)
    if (value == a) return value;
  throw std::runtime_error(fmt::format("`{}` is not a valid {}", value, field));
}

// No model asks for more (the compiler refuses them; the moving arc of order k needs
// k*(window-1) samples); larger or negative orders only come from a damaged file.
constexpr int kMaxOrder = kMaxDerivativeOrder;

// The deepest nesting of sums in functions, powers, der(), int() and guards a compiled model may
// hold (docs/compiled-model.md). The compiler writes at most the parser's 200 levels plus one per
// integration; a file nested deeper was not written by it and is refused as soon as the reader's
// recursion reaches the limit, in time linear in what it read (compiler/load_model.cpp refuses
// deeper JSON before it is parsed).
constexpr int kMaxCompiledNesting = 256;

struct Reader {
  std::shared_ptr<const SourceFile> source;
  std::set<std::string> signals;
  std::map<std::string, int> nonlinear;  // the parameters that may stand inside operations, by name
  mutable int depth = 0;  // of the sum being read: functions, powers, der(), int() and guards nest

  Span span(const json& j) const {
    if (j.is_null()) return {};
    const auto begin = integer<std::size_t>(j, "offset"), length = integer<std::size_t>(j, "length");
    if (begin > source->text.size() || length > source->text.size() - begin) throw std::runtime_error("a span outside the source text");
    return Span{source, begin, begin + length};
  }
  Number number(const json& j) const {
    if (j.contains("real")) return Number::real(j.at("real").get<double>());
    const auto den = integer<std::int64_t>(j, "den");
    if (den <= 0) throw std::runtime_error("a denominator is not positive");
    return Number::rational(integer<std::int64_t>(j, "num"), den);
  }
  ir::SumPtr sum_ptr(const json& j) const { return ir::share(sum(j)); }
  ir::Sum sum(const json& j) const {
    // Each level recurses here: a damaged file nested deeper than any compiler output is refused
    // before it can exhaust the stack.
    struct Level {
      int& depth;
      explicit Level(int& d) : depth(d) {
        if (++depth > kMaxCompiledNesting)
          throw std::runtime_error(fmt::format("an expression nested more than {} levels deep", kMaxCompiledNesting));
      }
      ~Level() { --depth; }
      Level(const Level&) = delete;
      Level& operator=(const Level&) = delete;
    } level(depth);
    std::vector<ir::Term> terms;
    for (const auto& t : j.at("terms")) {
      ir::Term term{number(t.at("coefficient")), {}, span(t.at("span"))};
      for (const auto& f : t.at("factors")) {
        const int power = integer<int>(f, "power");
        if (power == 0) throw std::runtime_error("a factor with power 0");
        term.factors.push_back({factor(f), power});
      }
      terms.push_back(ir::canonical(std::move(term)));
    }
    return ir::canonical(std::move(terms));
  }
  ir::Factor factor(const json& j) const {
    const auto kind = kind_from(j.at("kind").get<std::string>());
    if (!kind) throw std::runtime_error("unknown factor kind `" + j.at("kind").get<std::string>() + "`");
    if (*kind == FactorKind::parameter) {
      const auto name = j.at("name").get<std::string>();
      const auto it = nonlinear.find(name);
      if (it == nonlinear.end()) throw std::runtime_error("the parameter `" + name + "` stands inside an operation but is not marked nonlinear");
      return ir::Factor::plain(FactorKind::parameter, name, it->second);
    }
    if ((*kind == FactorKind::signal || *kind == FactorKind::initial_value) && !signals.count(j.at("name").get<std::string>()))
      throw std::runtime_error("a factor names the undeclared signal `" + j.at("name").get<std::string>() + "`");
    ir::Factor f{*kind, j.value("name", std::string()), j.contains("order") ? integer<int>(j, "order") : 0, {}, {}, {}, {}};
    if (f.order < 0 || f.order > kMaxOrder) throw std::runtime_error(fmt::format("a derivative order of {}", f.order));
    if (*kind == FactorKind::initial_value && !j.at("at").is_null()) f.at = number(j.at("at"));
    if (j.contains("exponent")) f.exponent = number(j.at("exponent"));
    if (j.contains("argument")) f.argument = sum_ptr(j.at("argument"));
    // What every pass after the reader takes for granted (the fuzzer found a function without its
    // argument reaching the unit pass): checked here, once.
    const bool takes_argument = *kind == FactorKind::function || *kind == FactorKind::power || *kind == FactorKind::derivative ||
                                *kind == FactorKind::integral;
    if (takes_argument && !f.argument) throw std::runtime_error(fmt::format("a `{}` factor without its argument", kind_name(*kind)));
    if (*kind == FactorKind::power && !j.contains("exponent")) throw std::runtime_error("a `power` factor without its exponent");
    static const std::set<std::string> functions{"sin", "cos", "exp", "log", "sqrt", "abs", "sign", "tanh"};
    if (*kind == FactorKind::function && !functions.count(f.name)) throw std::runtime_error("an unknown function `" + f.name + "`");
    if (*kind == FactorKind::guard)
      for (const auto& c : j.at("conditions")) {
        const std::string r = c.at("relation").get<std::string>();
        if (r != "<" && r != "<=" && r != ">" && r != ">=") throw std::runtime_error("unknown relation `" + r + "`");
        const ir::Relation rel = r == "<" ? ir::Relation::less : r == "<=" ? ir::Relation::less_equal
                               : r == ">" ? ir::Relation::greater : ir::Relation::greater_equal;
        f.conditions.push_back({sum_ptr(c.at("lhs")), rel, sum_ptr(c.at("rhs"))});
      }
    return f;
  }
};

ordered operations_json(const std::vector<ir::ParameterTerm>& terms, const ir::Model& m) {
  ordered operations = ordered::array();
  for (const auto& [index, op] : terms)
    operations.push_back(ordered{{"parameter", m.parameters[static_cast<std::size_t>(index)].name}, {"operation", sum_json(op)}});
  return operations;
}

ordered model_json(const ir::Model& m) {
  ordered equations = ordered::array();
  for (const auto& e : m.equations) {
    ordered eq{{"text", print(e, m)}, {"span", span_json(e.span)}, {"integrations", e.integrations},
               {"constants", e.integration.constants == ir::IntegrationRequest::Constants::initial ? "initial" : "fitted"},
               {"operations", operations_json(e.terms, m)}};
    eq["known"] = sum_json(e.known);
    if (e.weak) eq["weak"] = true;  // written only when set: files of the other forms stay as they were
    equations.push_back(std::move(eq));
  }
  return equations;
}

ordered plots_json(const ir::Model& m) {
  ordered plots = ordered::array();
  for (const auto& p : m.plots)
    plots.push_back(ordered{{"name", p.name}, {"text", print(p, m)}, {"span", span_json(p.span)}, {"signal", p.signal},
                            {"order", p.order}, {"operations", operations_json(p.terms, m)}, {"rest", sum_json(p.rest)},
                            {"truth", p.truth ? sum_json(*p.truth) : ordered(nullptr)}});
  return plots;
}

// Each parameter's index by its name (the first of a name, as Model::parameter_index): one look-up
// per operation instead of a search through every parameter, which was quadratic.
using ParameterIndices = std::unordered_map<std::string, int>;
ParameterIndices parameter_indices(const ir::Model& m) {
  ParameterIndices indices;
  for (std::size_t k = 0; k < m.parameters.size(); ++k) indices.emplace(m.parameters[k].name, static_cast<int>(k));
  return indices;
}

// Equations of the model from their JSON, parameters looked up by name in `indices`.
std::vector<ir::ParameterTerm> read_operations(const json& j, const ParameterIndices& indices, const Reader& r) {
  std::vector<ir::ParameterTerm> terms;
  for (const auto& o : j) {
    const auto index = indices.find(o.at("parameter").get<std::string>());
    if (index == indices.end()) throw std::runtime_error("an operation names an undeclared parameter");
    // A nonlinear parameter stands inside operations, never as one's parameter (normalize_pass).
    if (r.nonlinear.count(index->first)) throw std::runtime_error("the nonlinear parameter `" + index->first + "` multiplies an operation");
    terms.push_back({index->second, r.sum(o.at("operation"))});
  }
  return terms;
}

std::vector<ir::Equation> read_equations(const json& j, const ParameterIndices& m, const Reader& r) {
  std::vector<ir::Equation> equations;
  for (const auto& e : j) {
    ir::Equation eq;
    eq.span = r.span(e.at("span"));
    eq.integrations = integer<int>(e, "integrations");
    eq.weak = e.value("weak", false);
    eq.integration.constants = one_of(e, "constants", {"fitted", "initial"}) == "initial" ? ir::IntegrationRequest::Constants::initial
                                                                                           : ir::IntegrationRequest::Constants::fitted;
    eq.terms = read_operations(e.at("operations"), m, r);
    eq.known = r.sum(e.at("known"));
    equations.push_back(std::move(eq));
  }
  return equations;
}

// Test functions belong to the weak form's fitted equations alone, one on every term, at its top,
// to the power 1, of an order the weak form can reach: elsewhere nothing would integrate them away.
void check_test_functions(const ir::Model& m, const ir::Model& normalized) {
  const auto is_test_function = [](const ir::Factor& f) { return f.kind == FactorKind::test_function; };
  const auto none = [&](const ir::Sum& s, const std::string& where) {
    if (ir::any_factor(s, is_test_function)) throw std::runtime_error("a test function `phi_j` in " + where);
  };
  for (const auto& e : normalized.equations) {
    none(e.known, "the normalized equations");
    for (const auto& p : e.terms) none(p.operation, "the normalized equations");
  }
  if (m.weights) none(m.weights->value, "the weights");
  for (const auto& s : m.signals)
    if (s.definition) none(*s.definition, "the definition of `" + s.name + "`");
  for (const auto& p : m.plots) {
    none(p.rest, "plot `" + p.name + "`");
    if (p.truth) none(*p.truth, "plot `" + p.name + "`");
    for (const auto& t : p.terms) none(t.operation, "plot `" + p.name + "`");
  }
  for (const auto& e : m.equations) {
    std::vector<const ir::Sum*> sums{&e.known};
    for (const auto& p : e.terms) sums.push_back(&p.operation);
    for (const ir::Sum* s : sums) {
      if (!e.weak) {
        none(*s, "an equation that is not of the weak form");
        continue;
      }
      for (const auto& t : s->terms) {
        int found = 0;
        ir::Term rest = t;
        std::erase_if(rest.factors, [&](const auto& f) {
          if (f.first.kind != FactorKind::test_function) return false;
          if (f.second != 1 || f.first.order > kMaxWeakOrder) throw std::runtime_error("a test function of a power or order the weak form never writes");
          ++found;
          return true;
        });
        if (found != 1) throw std::runtime_error("a term of a weak-form equation without exactly one test function `phi_j`");
        none(ir::Sum{{rest}}, "the argument of a function, power, derivative, integral or guard");
      }
    }
  }
}

}  // namespace

std::string source_hash(const std::string& text) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return fmt::format("fnv1a64:{:016x}", h);
}

nlohmann::ordered_json to_json(const CompiledModel& c) {
  const ir::Model& m = c.integrated;
  ordered j;
  j["format"] = "sidc-compiled-model";
  j["version"] = kCompiledModelVersion;
  j["sidc_version"] = SIDC_VERSION;
  j["source"] = {{"path", c.source->name}, {"hash", source_hash(c.source->text)}, {"text", c.source->text}};
  j["model"] = m.name;
  ordered signals = ordered::array();
  for (const auto& s : m.signals) {
    ordered signal{{"name", s.name}, {"kind", s.kind == ir::Signal::Kind::input ? "input" : "output"},
                   {"definition", s.definition ? sum_json(*s.definition) : ordered(nullptr)}, {"span", span_json(s.span)}};
    // Written only when not smooth, so that files of models without held inputs stay as they were.
    if (s.hold != ir::Signal::Hold::smooth) signal["hold"] = to_string(s.hold);
    if (s.unit) signal["unit"] = to_string(*s.unit);  // likewise only when given
    signals.push_back(std::move(signal));
  }
  j["signals"] = std::move(signals);
  ordered parameters = ordered::array();
  for (const auto& p : m.parameters) {
    ordered parameter{{"name", p.name}, {"origin", origin_name(p.origin)}, {"equation", p.equation}, {"span", span_json(p.span)}};
    // Derived from the signals' units (compiler/unit_pass.cpp), for readers of the file; sidc
    // derives them again when it reads the file.
    if (p.unit) parameter["unit"] = to_string(*p.unit);
    // Written only when given, so that files of models without them stay as they were.
    if (p.guess) parameter["guess"] = number_json(*p.guess);
    if (p.nonlinear) parameter["nonlinear"] = true;
    parameters.push_back(std::move(parameter));
  }
  j["parameters"] = std::move(parameters);
  ordered constants = ordered::object();
  for (const auto& [name, value] : m.constants) constants[name] = number_json(value);
  j["constants"] = std::move(constants);
  j["settings"] = settings_json(m.settings);
  ordered data = ordered::array();
  for (const auto& d : m.data) {
    ordered bindings = ordered::object();
    for (const auto& [signal, column] : d.bindings) bindings[signal] = column;
    ordered exact = ordered::array();
    for (const auto& x : d.exact_derivatives) exact.push_back(ordered{{"signal", x.signal}, {"order", x.order}, {"column", x.column}});
    data.push_back(ordered{{"path", d.path}, {"bindings", std::move(bindings)}, {"exact_derivatives", std::move(exact)}});
  }
  j["data"] = std::move(data);
  j["weights_expression"] = m.weights ? ordered{{"expression", sum_json(m.weights->value)}, {"span", span_json(m.weights->span)}} : ordered(nullptr);
  j["plots"] = plots_json(m);
  j["normalized"] = model_json(c.normalized);
  j["equations"] = model_json(m);
  if (m.form_from_data) j["form_from_data"] = true;  // written only when set: other files stay as they were
  return j;
}

std::optional<CompiledModel> compiled_model_from_json(const nlohmann::ordered_json& j, const std::string& path, std::string& error) {
  try {
    if (j.value("format", std::string()) != "sidc-compiled-model") {
      error = render(cli_diag::not_a_compiled_model(path));
      return std::nullopt;
    }
    if (integer<int>(j, "version") != kCompiledModelVersion) {
      error = render(cli_diag::compiled_model_version(path, integer<int>(j, "version"), kCompiledModelVersion));
      return std::nullopt;
    }
    CompiledModel c;
    c.source = std::make_shared<const SourceFile>(j.at("source").at("path").get<std::string>(), j.at("source").at("text").get<std::string>());
    if (j.at("source").at("hash").get<std::string>() != source_hash(c.source->text))
      throw std::runtime_error("the source text does not match its hash");
    Reader r{c.source, {}, {}, 0};
    for (const auto& s : j.at("signals")) r.signals.insert(s.at("name").get<std::string>());
    ir::Model& m = c.integrated;
    m.name = j.at("model").get<std::string>();
    for (const auto& s : j.at("signals")) {
      ir::Signal sig;
      sig.name = s.at("name").get<std::string>();
      sig.kind = one_of(s, "kind", {"input", "output"}) == "input" ? ir::Signal::Kind::input : ir::Signal::Kind::output;
      sig.span = r.span(s.at("span"));
      sig.used = true;
      if (!s.at("definition").is_null()) sig.definition = r.sum(s.at("definition"));
      if (s.contains("hold")) {
        sig.hold = *ir::hold_from(one_of(s, "hold", {"smooth", "held", "linear"}));
        if (sig.kind != ir::Signal::Kind::input || sig.definition)
          throw std::runtime_error("the signal `" + sig.name + "` has a hold but is not a recorded input");
      }
      if (s.contains("unit")) {
        sig.unit = ir::parse_unit(s.at("unit").get<std::string>());
        if (!sig.unit) throw std::runtime_error("the unit of the signal `" + sig.name + "` does not read");
      }
      m.signals.push_back(std::move(sig));
    }
    for (const auto& p : j.at("parameters")) {
      const std::string origin = one_of(p, "origin", {"declared", "implicit", "integration_constant"});
      m.parameters.push_back({p.at("name").get<std::string>(),
                              origin == "implicit" ? ir::Parameter::Origin::implicit
                              : origin == "integration_constant" ? ir::Parameter::Origin::integration_constant
                                                                  : ir::Parameter::Origin::declared,
                              r.span(p.at("span")), integer<int>(p, "equation"), std::nullopt, std::nullopt, false});
      ir::Parameter& added = m.parameters.back();
      if (p.contains("guess")) added.guess = r.number(p.at("guess"));
      added.nonlinear = p.value("nonlinear", false);
      if (added.nonlinear && !added.guess) throw std::runtime_error("the nonlinear parameter `" + added.name + "` has no guess");
      if (added.nonlinear && added.origin == ir::Parameter::Origin::integration_constant)
        throw std::runtime_error("the integration constant `" + added.name + "` is marked nonlinear");
      if (added.nonlinear) r.nonlinear.emplace(added.name, static_cast<int>(m.parameters.size()) - 1);
    }
    for (const auto& [name, value] : j.at("constants").items()) m.constants.emplace(name, r.number(value));
    for (const auto& [key, value] : j.at("settings").at("as_written").items()) {
      const std::string text = value.get<std::string>();
      const SettingCheck check = check_setting(key, text);
      if (check.unknown_key) throw std::runtime_error("unknown setting `" + key + "`");
      if (!check.expected.empty()) throw std::runtime_error(fmt::format("`{}` is not a valid value for setting `{}`", text, key));
      m.settings.values[key] = {text, {}};
    }
    for (const auto& d : j.at("data")) {
      ir::DataSource source;
      source.path = d.at("path").get<std::string>();
      for (const auto& [signal, column] : d.at("bindings").items()) source.bindings.emplace_back(signal, column.get<std::string>());
      for (const auto& x : d.at("exact_derivatives")) {
        const std::string signal = x.at("signal").get<std::string>();
        if (!r.signals.count(signal)) throw std::runtime_error("an exact derivative names the undeclared signal `" + signal + "`");
        const int order = integer<int>(x, "order");
        if (order < 1 || order > kMaxOrder) throw std::runtime_error(fmt::format("an exact derivative of order {}", order));
        source.exact_derivatives.push_back({signal, order, x.at("column").get<std::string>(), {}});
      }
      m.data.push_back(std::move(source));
    }
    if (!j.at("weights_expression").is_null())
      m.weights = ir::WeightExpression{r.sum(j.at("weights_expression").at("expression")), r.span(j.at("weights_expression").at("span"))};
    // The derivative form before integration (what `sidc simulate` solves) shares everything but
    // the equations and the integration constants, which follow the model's own parameters.
    ir::Model normalized = m;
    std::erase_if(normalized.parameters, [](const ir::Parameter& p) { return p.origin == ir::Parameter::Origin::integration_constant; });
    const ParameterIndices normalized_indices = parameter_indices(normalized);
    for (const auto& p : j.at("plots")) {
      ir::PlotFunction plot;
      plot.name = p.at("name").get<std::string>();
      plot.span = r.span(p.at("span"));
      plot.signal = p.at("signal").get<std::string>();
      if (!r.signals.count(plot.signal)) throw std::runtime_error("a plot names the undeclared signal `" + plot.signal + "`");
      plot.order = integer<int>(p, "order");
      if (plot.order < 0 || plot.order > kMaxOrder) throw std::runtime_error(fmt::format("a plot against a derivative of order {}", plot.order));
      plot.terms = read_operations(p.at("operations"), normalized_indices, r);
      plot.rest = r.sum(p.at("rest"));
      if (!p.at("truth").is_null()) plot.truth = r.sum(p.at("truth"));
      normalized.plots.push_back(std::move(plot));
    }
    // Plots name the model's own parameters, whose indices are the same in both forms.
    m.plots = normalized.plots;
    normalized.equations = read_equations(j.at("normalized"), normalized_indices, r);
    m.equations = read_equations(j.at("equations"), parameter_indices(m), r);
    m.form_from_data = j.value("form_from_data", false);
    check_test_functions(m, normalized);
    c.normalized = std::move(normalized);
    return c;
  } catch (const std::exception& ex) {
    error = render(cli_diag::invalid_compiled_model(path, ex.what()));
    return std::nullopt;
  }
}

}  // namespace sidc
