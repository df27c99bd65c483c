#include "diagnostics/model_catalogue.hpp"

#include <algorithm>
#include <fmt/format.h>
#include <map>

namespace sidc::diag {
namespace {

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

}  // namespace

std::string nearest(std::string_view name, const std::vector<std::string>& candidates) {
  auto common_prefix = [&](const std::string& c) {
    std::size_t k = 0;
    while (k < c.size() && k < name.size() && c[k] == name[k]) ++k;
    return k;
  };
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(1, name.size() / 3) + 1;  // a plausible typo
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(name, c);
    if (d >= name.size()) continue;  // `z` -> `y` replaces everything: no help
    // Ties go to the longer common prefix (`sinn` -> `sin`, not `sign`), then alphabetical order.
    const bool better = d < best_distance ||
                        (d == best_distance && !best.empty() &&
                         (common_prefix(c) > common_prefix(best) || (common_prefix(c) == common_prefix(best) && c < best)));
    if (better) {
      best_distance = d;
      best = c;
    }
  }
  return best;
}

// ---- syntax ------------------------------------------------------------------------------------
// [grammar-owned section: parse errors]
namespace {

constexpr char operand_hint[] =
    "an operand is a number, a name such as `y'`, a call such as `sin(y)`, a family member such "
    "as `c[k]`, a guard such as `[y > 0]` or an expression in parentheses";
constexpr char continuation_hint[] =
    "a statement continues on the next line only after an operator, `(`, `[`, `,` or `=`";

// The hint for each expectation of the grammar (the names in `expected::`).
std::string syntax_hint(std::string_view what) {
  namespace e = expected;
  if (what == e::statement)
    return "a statement is a declaration (model, input, output, param, const, data, set) or an equation "
           "`left side = right side`";
  if (what == e::end_of_statement)
    return "write one statement per line or separate statements with `;`; between two operands write an "
           "operator such as `*`";
  if (what == e::expression || what == e::operand || what == e::factor) return operand_hint;
  if (what == e::equation_equals) return "an equation is written `left side = right side`, e.g. `a1*y'' + a2*y = x`";
  if (what == e::closing_parenthesis) return fmt::format("every `(` needs its `)`; {}", continuation_hint);
  if (what == e::closing_bracket) return fmt::format("every `[` needs its `]`; {}", continuation_hint);
  if (what == e::closing_quote) return "a string ends on the line where it starts";
  if (what == e::model_name) return "name the model as `model NAME`, e.g. `model quasi_linear`";
  if (what == e::signal_name)
    return "declare signals as `input x` or `output y1, y2`; an input may be given as an expression of t, "
           "as in `input x = 60*sin(4*pi*t)`";
  if (what == e::parameter_name) return "declare parameters as `param a1, a2` or a family as `param c[1..6]`";
  if (what == e::constant_name || what == e::constant_equals) return "declare constants as `const g = 9.81, L = 2*g`";
  if (what == e::integer || what == e::range_dots)
    return "a range is written with integers, as in `param c[1..6]` or `sum(k = 1..6, c[k]*y^k)`";
  if (what == e::file_name)
    return "write `data \"record.csv\"`, optionally followed by column bindings such as "
           "`(t = \"time\", y = \"displacement\")`";
  if (what == e::binding_signal || what == e::binding_equals || what == e::column_name)
    return "bind columns as `data \"record.csv\" (t = \"time\", y = \"displacement\")`";
  if (what == e::setting_name || what == e::setting_equals || what == e::setting_value)
    return "write a setting as `set NAME = VALUE`, e.g. `set integrate = 1`";
  if (what == e::comparison || what == e::comparison_operator)
    return "a guard is written `[y' <= 0]` or `[y > 0 and y' < 0]`; it compares with <, <=, > and >=";
  if (what == e::sum_parenthesis || what == e::sum_index || what == e::sum_equals || what == e::sum_comma)
    return "write a sum as `sum(k = 1..6, c[k]*y'^k)`; the bounds are integers";
  if (what == e::call_parenthesis) return "`der` and `int` are used as calls: `der(y^3, 1)`, `int(y)`";
  return {};
}

}  // namespace

Diagnostic syntax_expected(const Span& where, std::string_view what_was_expected, std::string_view found) {
  return error("syntax", where, fmt::format("expected {}, found {}", what_was_expected, found),
               syntax_hint(what_was_expected));
}

Diagnostic reserved_word_as_name(const Span& where, std::string_view word, std::string_view what_was_expected) {
  return error("reserved-word", where,
               fmt::format("expected {}, found the reserved word `{}`", what_was_expected, word),
               fmt::format("`{}` cannot name anything (reserved: model input output param const data set and sum "
                           "der int); choose another name such as `{}_1`",
                           word, word));
}

Diagnostic misspelled_keyword(const Span& where, std::string_view word, std::string_view keyword) {
  return error("unknown-statement", where, fmt::format("`{}` is not a statement keyword", word),
               fmt::format("did you mean `{}`?", keyword));
}

Diagnostic unterminated_string(const Span& where) {
  return error("unterminated-string", where, "the string starting here has no closing `\"`",
               "a string ends on the line where it starts; add the closing `\"`");
}

Diagnostic unexpected_character(const Span& where, unsigned char c) {
  if (c >= 0x20 && c < 0x7f)
    return error("unexpected-character", where, fmt::format("unexpected character `{}`", static_cast<char>(c)),
                 "names are letters, digits and `_`; operators are + - * / ^, comparisons < <= > >=; "
                 "see docs/language.md");
  return error("unexpected-character", where, fmt::format("unexpected byte 0x{:02x}", c),
               "model files are plain text (UTF-8 is allowed in comments and strings only); see docs/language.md");
}

Diagnostic non_ascii_character(const Span& where, std::string_view character) {
  return error("unexpected-character", where, fmt::format("unexpected character `{}`", character),
               "names use the ASCII letters, digits and `_`; other characters may appear only in comments and "
               "strings");
}

Diagnostic nesting_too_deep(const Span& where, int limit) {
  return error("nesting-too-deep", where, fmt::format("expression nested more than {} levels deep", limit),
               "split the expression, or name a part of it with `const`");
}

Diagnostic statement_too_long(const Span& where, std::size_t limit) {
  return error("statement-too-long", where, fmt::format("statement longer than {} characters", limit),
               "split it into several equations, or name parts of it with `const`");
}

Diagnostic too_many_statements(const Span& where, std::size_t limit) {
  return error("too-many-statements", where, fmt::format("the model has more than {} statements; the rest was not read", limit),
               "write families (`param c[1..50]`) and sums (`sum(k = 1..50, c[k]*y^k)`) instead of one statement each, "
               "or split the model into several files");
}

Diagnostic too_many_equations(const Span& where, std::size_t limit) {
  return error("too-many-equations", where, fmt::format("the model has more than {} equations; the rest was not read", limit),
               "write families and sums (`sum(k = 1..50, c[k]*y^k)`) instead of one equation each, or split the model into "
               "several files");
}

Diagnostic too_many_syntax_errors(const Span& where, int limit) {
  Diagnostic d = error("too-many-errors", where, fmt::format("stopped after {} syntax errors", limit),
                       "fix these first; the rest of the file was not read");
  d.severity = Severity::note;
  return d;
}

Diagnostic statement_not_read(const Span& where, std::string_view reason) {
  return error("statement-not-read", where, fmt::format("could not read this statement ({})", reason),
               "this is a problem of sidc, not of the model; please report it with the model file");
}

Diagnostic empty_model(const Span& where) {
  return error("empty-model", where, "the model has no equation",
               "write at least one equation, such as `a1*y'' + a2*y = x`");
}
// [end of grammar-owned section]

// ---- meaning -----------------------------------------------------------------------------------
// [compiler-owned section]
namespace {
std::string did_you_mean(std::string_view nearest) {
  return nearest.empty() ? std::string() : fmt::format("did you mean `{}`?", nearest);
}
std::string line_of(const Span& s) { return s.known() ? fmt::format("line {}", s.start().line) : std::string("elsewhere"); }
}  // namespace

Diagnostic unknown_name(const Span& where, std::string_view name, std::string_view nearest, bool parameters_declared) {
  std::string hint = did_you_mean(nearest);
  if (hint.empty())
    hint = parameters_declared ? fmt::format("declare it: `param {0}` for a parameter, `input {0}` or `output {0}` for a signal", name)
                               : fmt::format("declare it as a signal with `input {0}` or `output {0}`", name);
  return error("unknown-name", where, fmt::format("unknown name `{}`", name), hint);
}

Diagnostic unknown_function(const Span& where, std::string_view name, std::string_view nearest) {
  // A function of the usual maths library that sidc lacks is no typo of the one it is near
  // (`sinh` is not a misspelt `sin`): the list, and how to write it from the ones there are.
  static const std::map<std::string_view, std::string_view> rewrites{
      {"sinh", "sinh(x) = (exp(x) - exp(-x))/2"}, {"cosh", "cosh(x) = (exp(x) + exp(-x))/2"}, {"tan", "tan(x) = sin(x)/cos(x)"},
      {"cot", "cot(x) = cos(x)/sin(x)"},          {"sec", "sec(x) = 1/cos(x)"},                {"csc", "csc(x) = 1/sin(x)"},
      {"log10", "log10(x) = log(x)/log(10)"},     {"log2", "log2(x) = log(x)/log(2)"},         {"exp2", "exp2(x) = exp(x*log(2))"},
      {"pow", "pow(x, k) = x^k"},                 {"cbrt", "cbrt(x) = x^(1/3)"},               {"sqr", "sqr(x) = x^2"},
      {"asin", ""}, {"acos", ""}, {"atan", ""}, {"atan2", ""}, {"asinh", ""}, {"acosh", ""}, {"atanh", ""},
      {"floor", ""}, {"ceil", ""}, {"round", ""}, {"min", ""}, {"max", ""}, {"erf", ""}, {"gamma", ""}};
  std::string hint = did_you_mean(nearest);
  const char* list = "the functions are sin, cos, exp, log, sqrt, abs, sign, tanh, der and int";
  if (auto it = rewrites.find(name); it != rewrites.end())
    hint = it->second.empty() ? fmt::format("{}; `{}` is not one of them", list, name)
                              : fmt::format("{}; write `{}` with them: {}", list, name, it->second);
  if (hint.empty()) hint = list;
  return error("unknown-function", where, fmt::format("unknown function `{}`", name), hint);
}

Diagnostic wrong_arity(const Span& where, std::string_view function, std::string_view expected, std::size_t given) {
  return error("wrong-arity", where, fmt::format("`{}` takes {}, but {} {} given", function, expected, given, given == 1 ? "was" : "were"),
               fmt::format("write it as {}", function == "der" ? "`der(expression, order)`, e.g. `der(y^3, 1)`"
                                            : function == "int" ? "`int(expression)`, e.g. `int(y*x)`"
                                                                : fmt::format("`{}(expression)`", function)));
}

Diagnostic derivative_of_parameter(const Span& where, std::string_view name) {
  return error("derivative-of-parameter", where, fmt::format("`{}` is a parameter, a constant in time: its derivative is zero", name),
               "differentiate the signal it multiplies instead, e.g. `a1*y'`");
}

Diagnostic derivative_of_constant(const Span& where, std::string_view name) {
  return error("derivative-of-constant", where, fmt::format("`{}` is a constant: its derivative is zero", name),
               "remove the primes, or differentiate a signal");
}

Diagnostic nonlinear_parameter(const Span& where, std::string_view name, std::string_view how) {
  return error("nonlinear-parameter", where, fmt::format("parameter `{}` enters the equation nonlinearly: {}", name, how),
               fmt::format("each term may hold one parameter as a plain factor (`a1*y'^3`), which linear least squares fits "
                           "(thesis eq. 2-1.8): give the product a parameter of its own, or give `{0}` an initial guess "
                           "(`param {0} = 1.5`) and fit with `--refine`, which estimates it by the output error",
                           name));
}

Diagnostic no_known_term(const Span& where) {
  return error("no-known-term", where,
               "every term of this equation holds a parameter, so the least-squares solution is all zeros",
               "fix the scale: give one term a known coefficient (write `y''` rather than `m*y''`) or put the input "
               "on the other side without a parameter (`... = x`)");
}

Diagnostic no_parameter(const Span& where) {
  return error("no-parameter", where, "this equation has no parameter to determine",
               "multiply the operations whose coefficients are unknown by parameters, e.g. `a1*y'' + a2*y = x`");
}

Diagnostic declared_twice(const Span& where, std::string_view name, const Span& first) {
  return error("declared-twice", where, fmt::format("`{}` is declared twice", name),
               fmt::format("it was first declared on {}; remove one of the declarations or rename one", line_of(first)));
}

Diagnostic reserved_name(const Span& where, std::string_view name) {
  return error("reserved-name", where, fmt::format("`{}` is a built-in name and cannot be declared", name),
               "built-ins are t, t0, tau, pi, the functions and der, int, sum; choose another name");
}

Diagnostic output_unused(const Span& where, std::string_view name) {
  return error("output-unused", where, fmt::format("output `{}` is never used in an equation", name),
               "use it in an equation, or remove it from the `output` declaration");
}

Diagnostic input_unused(const Span& where, std::string_view name) {
  Diagnostic d = error("input-unused", where, fmt::format("input `{}` is never used in an equation", name),
                       "remove it from the `input` declaration if it plays no part");
  d.severity = Severity::warning;
  return d;
}

Diagnostic dependent_operations(const Span& where, std::string_view first, std::string_view second, std::string_view operation) {
  return error("dependent-operations", where,
               fmt::format("parameters `{}` and `{}` multiply the same operation `{}`: they cannot be told apart", first, second, operation),
               fmt::format("keep one parameter for `{}` (their sum is all the data can determine)", operation));
}

Diagnostic unknown_setting(const Span& where, std::string_view key, std::string_view nearest) {
  std::string hint = did_you_mean(nearest);
  if (hint.empty()) hint = "the settings are listed in docs/language.md";
  return error("unknown-setting", where, fmt::format("unknown setting `{}`", key), hint);
}

Diagnostic bad_setting_value(const Span& where, std::string_view key, std::string_view value, std::string_view expected) {
  return error("bad-setting-value", where, fmt::format("`{}` is not a valid value for `{}`", value, key),
               fmt::format("`{}` takes {}", key, expected));
}

Diagnostic setting_repeated(const Span& where, std::string_view key, const Span& first) {
  return error("setting-repeated", where, fmt::format("`{}` is set twice", key),
               fmt::format("it was first set on {}; keep one (command-line options override the file)", line_of(first)));
}

Diagnostic setting_after_last_equation(const Span& where, std::string_view key) {
  Diagnostic d = error("setting-after-last-equation", where, fmt::format("`set {}` comes after the last equation and applies to nothing", key),
                       fmt::format("`set {}` applies to the equations after it: move it above the equation(s) it is meant for", key));
  d.severity = Severity::warning;
  return d;
}

Diagnostic not_a_family(const Span& where, std::string_view name, bool is_signal) {
  return error("not-a-family", where, fmt::format("`{}` is not an indexed parameter family", name),
               is_signal ? fmt::format("`{0}` is a signal; to multiply it by a guard write `{0}*[...]`", name)
                         : fmt::format("declare a family with `param {}[1..6]`", name));
}

Diagnostic family_needs_index(const Span& where, std::string_view name) {
  return error("family-needs-index", where, fmt::format("`{}` is a parameter family: say which member", name),
               fmt::format("write `{}[1]`, or `{}[k]` inside `sum(k = ..., ...)`", name, name));
}

Diagnostic index_out_of_range(const Span& where, std::string_view family, long long index, int from, int to) {
  return error("index-out-of-range", where, fmt::format("`{}[{}]` is outside the family `{}[{}..{}]`", family, index, family, from, to),
               "widen the family's declared range or correct the index");
}

Diagnostic index_not_integer(const Span& where) {
  return error("index-not-integer", where, "an index must be an integer, made of numbers and `sum` indices",
               "write e.g. `c[3]` or `c[k + 6]`");
}

Diagnostic bad_range(const Span& where, int from, int to) {
  return error("bad-range", where, fmt::format("the range {}..{} is empty", from, to), "write the smaller bound first, e.g. `1..6`");
}

Diagnostic range_too_large(const Span& where, long long count, int limit) {
  return error("range-too-large", where, fmt::format("the range has {} members; at most {} are allowed", count, limit),
               "a model this large is surely a typo in a bound");
}

Diagnostic index_shadows(const Span& where, std::string_view name) {
  return error("index-shadows", where, fmt::format("the sum index `{}` hides another name", name),
               "choose an index name that is not a signal, parameter, constant or outer index (e.g. `k`)");
}

Diagnostic bad_initial_value(const Span& where, std::string_view signal) {
  return error("bad-initial-value", where, fmt::format("the initial value `{}(...)` needs one time: a number or `t0`", signal),
               fmt::format("write `{}(0)` for the record's value at t = 0, or `{}(t0)` at the start of the fit window", signal, signal));
}

Diagnostic delay_not_supported(const Span& where, std::string_view signal) {
  return error("delay-not-supported", where, fmt::format("`{}` at a time that moves with t is a delay, which sidc does not support", signal),
               fmt::format("shift the record's column by the delay and bind the shifted one (`data \"r.csv\" ({0} = \"{0}_delayed\")`); "
                           "`{0}(0)` and `{0}(t0)` are values at a fixed time", signal));
}

Diagnostic not_callable(const Span& where, std::string_view name, std::string_view what) {
  return error("not-callable", where, fmt::format("`{}` is {} and cannot be called", name, what),
               "only functions, der, int and signals (for initial values such as `y(0)`) take arguments");
}

Diagnostic bad_derivative_order(const Span& where) {
  return error("bad-derivative-order", where, "the order of `der` must be a positive whole number",
               "write e.g. `der(y*x, 2)`");
}

Diagnostic exponent_not_constant(const Span& where) {
  return error("exponent-not-constant", where, "an exponent must be a constant number",
               "a power of a signal such as `y^2` or `abs(y')^1.5` is fine; for `y^x` write `exp(x*log(y))`");
}

Diagnostic division_by_zero(const Span& where) {
  return error("division-by-zero", where, "division by zero", "");
}

Diagnostic expression_too_large(const Span& where, std::size_t limit) {
  return error("expression-too-large", where, fmt::format("expanding this expression gives more than {} terms", limit),
               "write the product out more compactly, or name a part with `const`");
}

Diagnostic derivative_too_large(const Span& where, std::size_t limit) {
  return error("derivative-too-large", where,
               fmt::format("this derivative takes more than {} nodes (terms and factors) to write out, the most a model may build", limit),
               "lower the order or nest fewer functions; each order of a nested function multiplies its terms");
}

Diagnostic expansion_too_large(const Span& where, std::size_t limit) {
  return error("expansion-too-large", where,
               fmt::format("expanding this builds more than {} nodes (terms and factors), the most a model may build", limit),
               "write the product or power out more compactly, or name a part with `const`");
}

Diagnostic model_too_many_nodes(const Span& where, std::size_t limit) {
  return error("model-too-many-nodes", where,
               fmt::format("the model, written out, reaches more than {} nodes (terms and factors) here", limit),
               "write fewer or smaller equations, or split the model into several files");
}

Diagnostic sum_too_large(const Span& where, long double count, std::size_t limit) {
  return error("sum-too-large", where,
               fmt::format("this sum would write out its body {:.3g} times (its range times the ranges of the sums "
                           "around it), more than the {} nodes a model may build",
                           static_cast<double>(count), limit),
               "use shorter ranges, or fewer sums inside sums");
}

Diagnostic number_overflows(const Span& where, std::string_view what) {
  return error("number-overflows", where, fmt::format("{} overflows: it is beyond about 1.8e308", what),
               "use a smaller number; no record can be evaluated with it");
}

Diagnostic exponent_too_large(const Span& where, std::string_view exponent, long long limit) {
  return error("exponent-too-large", where, fmt::format("the exponent {} is beyond {}", exponent, limit),
               fmt::format("a power of a signal must lie between -{0} and {0}; larger ones overflow on any record", limit));
}

Diagnostic derivative_order_too_high(const Span& where, long long order, int limit) {
  return error("derivative-order-too-high", where,
               fmt::format("a derivative of order {} is beyond the highest sidc estimates, {}", order, limit),
               "count the primes; a record cannot give derivatives that high");
}

Diagnostic empty_fit_window_setting(const Span& where, std::string_view from, std::string_view to, const Span& other) {
  return error("empty-fit-window", where, fmt::format("the fit window is empty: `from` = {} is after `to` = {}", from, to),
               fmt::format("the other end is set on {}; `from` must be the earlier time", line_of(other)));
}

Diagnostic not_a_number(const Span& where, std::string_view what) {
  return error("not-a-number", where, fmt::format("{} must be a number", what),
               "use numbers, `pi`, other constants and functions of them");
}

Diagnostic input_definition_uses_signal(const Span& where, std::string_view input, std::string_view name) {
  std::string hint = "an input given as an expression may use only t, numbers and constants, e.g. `input x = 60*sin(4*pi*t)`";
  // A guard of t is how a step would be written: say what does the job instead.
  if (name == "[...]")
    hint += fmt::format("; for a step, record `{0}` as a column of the data and declare it `input {0} held`, or write the step "
                        "with sign(): `100 + 15*(1 + sign(t - 10))`",
                        input);
  return error("input-definition", where, fmt::format("input `{}` is defined by an expression that uses `{}`", input, name), hint);
}

Diagnostic binding_unknown_signal(const Span& where, std::string_view name, std::string_view nearest) {
  std::string hint = did_you_mean(nearest);
  if (hint.empty()) hint = "bind declared signals, or `t` for the time column";
  return error("binding-unknown-signal", where, fmt::format("`{}` is not a declared signal", name), hint);
}

Diagnostic binding_repeated(const Span& where, std::string_view name) {
  return error("binding-repeated", where, fmt::format("`{}` is bound twice in this data statement", name), "keep one binding");
}

Diagnostic binding_of_defined_input(const Span& where, std::string_view name) {
  return error("binding-of-defined-input", where, fmt::format("input `{}` is defined by an expression, so it has no column", name),
               "remove the binding, or the definition in the `input` declaration");
}

Diagnostic static_model_integrated(const Span& where, int times) {
  return error("static-model-integrated", where,
               fmt::format("cannot integrate {} time{}: this equation has no derivative, integral or time in it", times, times == 1 ? "" : "s"),
               "integration rewrites differential equations (thesis section 2-2); use `--integrate 0` for a static model");
}

Diagnostic static_model_weak(const Span& where) {
  return error("static-model-weak", where, "cannot write this equation in weak form: it has no derivative, integral or time in it",
               "the weak form integrates differential equations against test functions over time; use `set form = derivative` "
               "(or no `set form`) for a static model");
}

Diagnostic unknown_hold(const Span& where, std::string_view signal, std::string_view word) {
  return error("unknown-hold", where, fmt::format("`{}` after the input `{}` is not a hold", word, signal),
               "write `held` (each sample's value holds until the next), `linear` (straight between samples) or "
               "`smooth` (the default); separate several signals with commas: `input x, u`");
}

Diagnostic bad_unit(const Span& where, std::string_view signal, std::string_view expected) {
  return error("bad-unit", where, fmt::format("the unit of `{}` does not read: {}", signal, expected),
               "write a product of unit symbols with whole or parenthesised exponents, e.g. `[m]`, `[N*m]`, `[m/s^2]`, "
               "`[kg*m^(1/2)]`, or `[1]` for a dimensionless signal (docs/language.md, \"Units\")");
}

namespace {
// " (line N)" for a second place on another line than the first.
std::string at_line(const Span& s, const Span& where) {
  return s.known() && (!where.known() || s.start().line != where.start().line) ? fmt::format(" (line {})", s.start().line) : std::string();
}
}  // namespace

Diagnostic unit_mismatch(const Span& where, std::string_view unit, std::string_view expected_unit, const Span& expected_at) {
  return error("unit-mismatch", where,
               fmt::format("this term has the unit {}, but the terms it is added to have {}{}", unit, expected_unit,
                           at_line(expected_at, where)),
               "terms without a parameter must agree in unit, as nothing can absorb the difference: check the "
               "signals' declared units, or give the term a parameter to estimate");
}

Diagnostic operation_unit_mismatch(const Span& where, std::string_view parameter, std::string_view unit,
                                   std::string_view other_unit, const Span& other_at) {
  return error("operation-unit-mismatch", where,
               fmt::format("this term multiplies `{}` with the unit {}, another of its terms{} has {}", parameter, unit,
                           at_line(other_at, where), other_unit),
               fmt::format("`{}` can have one unit only: give the terms separate parameters, or check the signals' "
                           "declared units",
                           parameter));
}

Diagnostic function_of_unit(const Span& where, std::string_view function, std::string_view unit) {
  return error("function-of-unit", where,
               fmt::format("the argument of `{}` has the unit {}; `{}` takes a dimensionless one", function, unit, function),
               "divide by a quantity of the same unit, declare the signal in radians (`[rad]`, dimensionless), or "
               "write a number factor, which carries the unit (`sin(2*pi*t)` reads as 2*pi rad/s times t)");
}

Diagnostic parameter_unit_conflict(const Span& where, std::string_view parameter, std::string_view unit,
                                   std::string_view other_unit, const Span& other_at) {
  return error("parameter-unit-conflict", where,
               fmt::format("`{}` needs the unit {} here and {} in the equation{}", parameter, unit, other_unit, at_line(other_at, where)),
               "a parameter has one unit: use two parameters, or check the signals' declared units");
}

Diagnostic hold_on_output(const Span& where, std::string_view signal, std::string_view word) {
  return error("hold-on-output", where, fmt::format("the output `{}` cannot be `{}`", signal, word),
               "a hold says how an input was applied between samples; outputs are smooth responses, estimated by "
               "the moving arc. Declare the signal with `input` if the process was driven by it");
}

Diagnostic hold_on_defined_input(const Span& where, std::string_view signal, std::string_view word) {
  return error("hold-on-defined-input", where, fmt::format("the input `{}` is given as an expression of t and cannot also be `{}`", signal, word),
               "a hold applies to a recorded input's samples; drop the expression and bind `" + std::string(signal) +
                   "` to a column of the record, or drop the hold");
}

Diagnostic derivative_of_held_input(const Span& where, std::string_view signal, std::string_view hold, std::string_view written) {
  const bool held = hold == "held";
  return error("derivative-of-held-input", where,
               fmt::format("`{}` is a derivative of the {} input `{}`, {}", written, hold, signal,
                           held ? "which has none between samples, only a jump at each" : "whose slope jumps at every sample"),
               "write the model in integrated or weak form (`set integrate = 1`, `set form = weak`), where a term linear in the "
               "input's derivative is integrated away exactly (a product such as `x'*y` is not: rewrite it), or declare the "
               "input `smooth` if it really moved smoothly");
}

Diagnostic unknown_pass(std::string_view name, std::string_view nearest, std::string_view passes) {
  std::string hint = did_you_mean(nearest);
  return error("unknown-pass", {}, fmt::format("unknown pass `{}`", name),
               hint.empty() ? fmt::format("the passes are: {}", passes) : hint + fmt::format(" (the passes are: {})", passes));
}

Diagnostic integrate_option_invalid(std::string_view value) {
  return error("bad-integrate-option", {}, fmt::format("`--integrate {}` is not a number of integrations", value),
               "give a whole number from 0 to 8, or `auto`");
}

Diagnostic no_signal(const Span& where) {
  return error("no-signal", where, "this equation uses no signal", "an equation relates signals, e.g. `a1*y' + a2*y = x`");
}

Diagnostic parameter_not_allowed(const Span& where, std::string_view name, std::string_view what) {
  return error("parameter-not-allowed", where, fmt::format("parameter `{}` cannot appear in {}: it must be known before the fit", name, what),
               "use signals, t, numbers and constants here");
}

Diagnostic weights_unknown_name(const Span& where, std::string_view name, std::string_view nearest) {
  std::string hint = fmt::format("a record column is written in quotes: `set weights = \"{}\"`", name);
  if (!nearest.empty()) hint = fmt::format("did you mean `{}`? A record column is written in quotes: `set weights = \"{}\"`", nearest, name);
  return error("weights-unknown-name", where, fmt::format("unknown name `{}` in the weights expression", name), hint);
}

Diagnostic plot_argument_not_signal(const Span& where, std::string_view plot, std::string_view name, std::string_view nearest) {
  std::string hint = did_you_mean(nearest);
  if (hint.empty()) hint = "a plotted function is drawn against a declared signal or one of its derivatives, e.g. `plot damper(y') = ...`";
  return error("plot-argument", where, fmt::format("plot `{}` is drawn against `{}`, which is no signal of the model", plot, name), hint);
}

Diagnostic plot_uses_other_quantity(const Span& where, std::string_view plot, std::string_view quantity, std::string_view argument) {
  return error("plot-other-quantity", where,
               fmt::format("plot `{}` is a function of `{}` alone, but this term uses `{}`", plot, argument, quantity),
               "a plotted function is drawn over the range of its one argument; make a separate plot for each quantity");
}

Diagnostic plot_without_parameter(const Span& where, std::string_view plot) {
  return error("plot-without-parameter", where, fmt::format("plot `{}` uses no parameter of the model, so nothing fitted is drawn", plot),
               "write the function with the equations' parameters, e.g. `plot damper(y') = c1*y' + c2*y'^3`");
}

Diagnostic plot_parameter_not_fitted(const Span& where, std::string_view plot, std::string_view parameter) {
  return error("plot-parameter-not-fitted", where,
               fmt::format("plot `{}` uses parameter `{}`, which no equation uses, so the fit gives it no value", plot, parameter),
               "draw functions of the parameters the equations estimate");
}

Diagnostic simulate_integral(const Span& where, std::string_view term) {
  return error("simulate-integral", where, fmt::format("`{}` cannot be simulated: an integral of the solution is not a state", term),
               "simulate the derivative form of the model (`set integrate = 0`), which sidc fit keeps as the normalized equations");
}

Diagnostic simulate_estimated_derivative(const Span& where, std::string_view term) {
  return error("simulate-estimated-derivative", where,
               fmt::format("`{}` cannot be simulated: der() is estimated from recorded data, which a simulation does not have", term),
               "write the derivative with primes (`y''`), or expand it so that it has a symbolic derivative");
}

Diagnostic simulate_derivative_of_held_input(const Span& where, std::string_view signal, std::string_view hold, std::string_view written) {
  return error("simulate-derivative-of-held-input", where,
               fmt::format("`{}` cannot be simulated: the {} input `{}` has no derivative between samples to estimate", written, hold, signal),
               fmt::format("write the equation without it, moving the input into a new state (y' + a*y = c*{0}' is z' + a*z = -a*c*{0} "
                           "with y = z + c*{0}), or declare the input `smooth` if it really moved smoothly",
                           signal));
}

Diagnostic highest_derivative_nonlinear(const Span& where, std::string_view derivative, std::string_view how) {
  return error("highest-derivative-nonlinear", where,
               fmt::format("the equation cannot be solved for `{}`: it enters {}", derivative, how),
               "simulation needs every equation linear in its output's highest derivative, as in `m*y'' + c(y') + k(y) = x`");
}

Diagnostic simulate_static_output(const Span& where, std::string_view output) {
  return error("simulate-static-output", where, fmt::format("output `{}` has no derivative in the equations: a static model, nothing to simulate", output),
               "sidc simulate solves differential equations; a static model is evaluated, not simulated");
}

Diagnostic simulate_equation_count(const Span& where, std::size_t equations, std::size_t outputs) {
  return error("simulate-equation-count", where,
               fmt::format("{} equation{} for {} output{}: a simulation needs one equation per output", equations, equations == 1 ? "" : "s",
                           outputs, outputs == 1 ? "" : "s"),
               "give each output one equation that contains its highest derivative");
}

Diagnostic highest_derivatives_unmatched(const Span& where, std::string_view derivatives) {
  return error("highest-derivatives-unmatched", where,
               fmt::format("the equations cannot be solved for {}: no equation is left for some of them", derivatives),
               "each output's highest derivative must appear in its own equation (an equation without any highest derivative is a constraint, not an equation of motion)");
}

Diagnostic simulate_initial_value_term(const Span& where, std::string_view term) {
  return error("simulate-initial-value", where, fmt::format("`{}` has no value in this simulation", term),
               "a value at a time other than t0 needs a record; give one with --data, or write the number");
}

Diagnostic drift_dominates(const Span& where, std::size_t number, int integrations, std::string_view what, std::string_view record, double share,
                           std::string_view others) {
  Diagnostic d = error(
      "drift-dominates", where,
      fmt::format("equation {} is integrated {} time{} and drift dominates it: on `{}`, {:.4g}% of what the integration constants leave of {} "
                  "is a polynomial of degree {} in t{}; the estimates rest on the remaining {:.2g}%",
                  number, integrations, integrations == 1 ? "" : "s", record, 100 * share, what, integrations, others.empty() ? "" : fmt::format(" ({})", others),
                  100 * (1 - share)),
      integrations > 1 ? fmt::format("fit a shorter window (--from/--to, `set from`/`set to`), use the weak form (`set form = weak`), or integrate fewer "
                                     "times (`set integrate = {}`)",
                                     integrations - 1)
                       : std::string("fit a shorter window (--from/--to, `set from`/`set to`), use the weak form (`set form = weak`), or the derivative "
                                     "form (`set integrate = 0`)"));
  d.severity = Severity::warning;
  return d;
}

Diagnostic known_side_zero(const Span& where, std::size_t number, std::string_view known, std::string_view records) {
  return error("known-side-zero", where,
               fmt::format("the known side `{}` of equation {} is zero on every row of {}: every parameter would be 0 and the fit "
                           "statistics meaningless",
                           known, number, records),
               "check that the record's column holds the signal (not a column of zeros), or fit a record in which it varies");
}

Diagnostic statistics_not_finite(const Span& where, std::string_view equations, std::string_view statistics) {
  Diagnostic d = error("statistics-not-finite", where,
                       fmt::format("the fit of {} leaves {}", equations, statistics),
                       "the other statistics are computed in extended precision and hold; for every number to fit in a double, give "
                       "the record in units that keep its values between about 1e-150 and 1e150");
  d.severity = Severity::warning;
  return d;
}

}  // namespace sidc::diag
