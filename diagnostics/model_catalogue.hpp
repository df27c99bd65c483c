// Every message sidc prints about model text, one named constructor each (stanc3's
// Semantic_error.ml). Passes never format wording themselves; each constructor has a bad-input
// golden test in tests/golden/bad/. Codes are stable: tests rely on them.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "diagnostics/diagnostic.hpp"

namespace sidc::diag {

// The nearest of `candidates` to `name` by edit distance, or "" when none is close enough to be
// a plausible typo. Used for every "did you mean".
std::string nearest(std::string_view name, const std::vector<std::string>& candidates);

// ---- syntax (grammar/) -------------------------------------------------------------------------
// [grammar-owned section: parse errors]

// What the parser expected, in the words its messages use. grammar/model_def.hpp names its rules
// with these (X3 reports a failed expectation by the rule's name), and syntax_expected() gives
// each its hint.
namespace expected {
inline constexpr char statement[] = "a statement such as `param a1` or `a1*y' + y = x`";
inline constexpr char end_of_statement[] = "the end of the statement";
inline constexpr char expression[] = "an expression such as `a1*y'' + a2*y`";
inline constexpr char operand[] = "an operand such as `a1*y'` or `(y - 1)`";
inline constexpr char factor[] = "a factor such as `y'`, `2.5` or `(y - 1)`";
inline constexpr char equation_equals[] = "`=` between the two sides of an equation";
inline constexpr char closing_parenthesis[] = "a closing `)`";
inline constexpr char closing_bracket[] = "a closing `]`";
inline constexpr char closing_quote[] = "a closing `\"`";
inline constexpr char model_name[] = "a model name";
inline constexpr char signal_name[] = "a signal name";
inline constexpr char parameter_name[] = "a parameter name";
inline constexpr char constant_name[] = "a constant name";
inline constexpr char constant_equals[] = "`=` and the constant's value";
inline constexpr char integer[] = "an integer";
inline constexpr char range_dots[] = "`..` between the bounds of a range";
inline constexpr char file_name[] = "a quoted file name such as `\"record.csv\"`";
inline constexpr char binding_signal[] = "a signal name bound to a column, as in `y = \"displacement\"`";
inline constexpr char binding_equals[] = "`=` between a signal and its column";
inline constexpr char column_name[] = "a column name, quoted or plain";
inline constexpr char setting_name[] = "a setting name such as `integrate`";
inline constexpr char setting_equals[] = "`=` between the setting and its value";
inline constexpr char setting_value[] = "a value, as in `set integrate = 1`";
inline constexpr char comparison[] = "a comparison such as `y' <= 0`";
inline constexpr char comparison_operator[] = "a comparison operator `<`, `<=`, `>` or `>=`";
inline constexpr char sum_parenthesis[] = "`(` after `sum`";
inline constexpr char sum_index[] = "the summation index, as in `sum(k = 1..6, c[k]*y^k)`";
inline constexpr char sum_equals[] = "`=` after the summation index";
inline constexpr char sum_comma[] = "`,` before the summand";
inline constexpr char call_parenthesis[] = "`(` after `der` or `int`";
inline constexpr char weights_value[] = "a quoted column name or an expression, as in `set weights = \"w\"` or `set weights = 1/(1 + y'^2)`";
inline constexpr char plot_name[] = "a name for the plotted function, as in `plot damper(y') = ...`";
inline constexpr char plot_parenthesis[] = "`(` and the signal the function is drawn against, as in `plot damper(y')`";
inline constexpr char plot_argument[] = "the signal the function is drawn against, as in `plot damper(y')`";
inline constexpr char plot_equals[] = "`=` and the function's expression in the model's parameters";
}  // namespace expected

// How a message names what it found where no token is.
namespace found {
inline constexpr char end_of_line[] = "the end of the line";
inline constexpr char end_of_file[] = "the end of the file";
}  // namespace found

// `found` is a token in backquotes (or found::end_of_line ...); the hint depends on `expected`.
Diagnostic syntax_expected(const Span& where, std::string_view what_was_expected, std::string_view found);
// A name was expected and the user wrote a reserved word (`param model`).
Diagnostic reserved_word_as_name(const Span& where, std::string_view word, std::string_view what_was_expected);
// A statement starts with a word close to a statement keyword and is no equation (`parm a1`).
Diagnostic misspelled_keyword(const Span& where, std::string_view word, std::string_view keyword);
// A string literal without its closing quote; `where` spans from the opening quote.
Diagnostic unterminated_string(const Span& where);
Diagnostic unexpected_character(const Span& where, unsigned char c);
// A valid UTF-8 character outside comments and strings, such as `é` in a name.
Diagnostic non_ascii_character(const Span& where, std::string_view character);
Diagnostic nesting_too_deep(const Span& where, int limit);
Diagnostic statement_too_long(const Span& where, std::size_t limit);
// The file holds more statements than the parser reads (`where`: the first one past the limit).
Diagnostic too_many_statements(const Span& where, std::size_t limit);
Diagnostic too_many_equations(const Span& where, std::size_t limit);
// A note ending the list when the parser stopped after `limit` errors.
Diagnostic too_many_syntax_errors(const Span& where, int limit);
// A statement the parser could not read for a reason it cannot name (an internal failure such
// as running out of memory); never expected on any input.
Diagnostic statement_not_read(const Span& where, std::string_view reason);
Diagnostic empty_model(const Span& where);
// [end of grammar-owned section]

// ---- meaning (compiler/declare_pass.cpp, lower_pass.cpp, normalize_pass.cpp, integrate_pass.cpp) ---------------------------------------------------------
// [compiler-owned section]
Diagnostic unknown_name(const Span& where, std::string_view name, std::string_view nearest, bool parameters_declared);
Diagnostic unknown_function(const Span& where, std::string_view name, std::string_view nearest);
Diagnostic wrong_arity(const Span& where, std::string_view function, std::string_view expected, std::size_t given);
Diagnostic derivative_of_parameter(const Span& where, std::string_view name);
Diagnostic derivative_of_constant(const Span& where, std::string_view name);
Diagnostic nonlinear_parameter(const Span& where, std::string_view name, std::string_view how);
Diagnostic no_known_term(const Span& where);
Diagnostic no_parameter(const Span& where);
Diagnostic declared_twice(const Span& where, std::string_view name, const Span& first);
Diagnostic reserved_name(const Span& where, std::string_view name);
Diagnostic output_unused(const Span& where, std::string_view name);
Diagnostic input_unused(const Span& where, std::string_view name);
Diagnostic dependent_operations(const Span& where, std::string_view first, std::string_view second, std::string_view operation);
Diagnostic unknown_setting(const Span& where, std::string_view key, std::string_view nearest);
Diagnostic bad_setting_value(const Span& where, std::string_view key, std::string_view value, std::string_view expected);
Diagnostic setting_repeated(const Span& where, std::string_view key, const Span& first);
// A warning: `set form|integrate|constants` applies to the equations after it, and none follows.
Diagnostic setting_after_last_equation(const Span& where, std::string_view key);
Diagnostic not_a_family(const Span& where, std::string_view name, bool is_signal);
Diagnostic family_needs_index(const Span& where, std::string_view name);
Diagnostic index_out_of_range(const Span& where, std::string_view family, long long index, int from, int to);
Diagnostic index_not_integer(const Span& where);
Diagnostic bad_range(const Span& where, int from, int to);
Diagnostic range_too_large(const Span& where, long long count, int limit);
Diagnostic index_shadows(const Span& where, std::string_view name);
Diagnostic bad_initial_value(const Span& where, std::string_view signal);
// `u(t - 0.05)`: a signal at a time that moves with t, a delay, which the linear form cannot hold.
Diagnostic delay_not_supported(const Span& where, std::string_view signal);
Diagnostic not_callable(const Span& where, std::string_view name, std::string_view what);
Diagnostic bad_derivative_order(const Span& where);
Diagnostic exponent_not_constant(const Span& where);
Diagnostic division_by_zero(const Span& where);
Diagnostic expression_too_large(const Span& where, std::size_t limit);
// Budgets of symbolic work, counted in nodes (a term or a factor; what a function, power, der(),
// int() or guard holds counts again wherever it stands, as printing writes it out).
Diagnostic derivative_too_large(const Span& where, std::size_t limit);
Diagnostic expansion_too_large(const Span& where, std::size_t limit);
Diagnostic model_too_many_nodes(const Span& where, std::size_t limit);
// `count`: how many times the body would be expanded (this range times the ranges around it).
Diagnostic sum_too_large(const Span& where, long double count, std::size_t limit);
// A constant (`what`: "the exponent", "the power") outside the range of double.
Diagnostic number_overflows(const Span& where, std::string_view what);
Diagnostic exponent_too_large(const Span& where, std::string_view exponent, long long limit);
Diagnostic derivative_order_too_high(const Span& where, long long order, int limit);
// `set from` not before `set to`: the fit window is empty (`where`: the later of the two settings).
Diagnostic empty_fit_window_setting(const Span& where, std::string_view from, std::string_view to, const Span& other);
Diagnostic not_a_number(const Span& where, std::string_view what);
Diagnostic input_definition_uses_signal(const Span& where, std::string_view input, std::string_view name);
Diagnostic binding_unknown_signal(const Span& where, std::string_view name, std::string_view nearest);
Diagnostic binding_repeated(const Span& where, std::string_view name);
Diagnostic binding_of_defined_input(const Span& where, std::string_view name);
Diagnostic static_model_weak(const Span& where);
// `input x held`: the word after a signal's name is not a hold, or sits on an output or on an
// input given as an expression of t; a held or linear input's derivative left after the form pass.
Diagnostic unknown_hold(const Span& where, std::string_view signal, std::string_view word);
Diagnostic hold_on_output(const Span& where, std::string_view signal, std::string_view word);
Diagnostic hold_on_defined_input(const Span& where, std::string_view signal, std::string_view word);
Diagnostic derivative_of_held_input(const Span& where, std::string_view signal, std::string_view hold, std::string_view written);
Diagnostic static_model_integrated(const Span& where, int times);
// Units (`output theta [rad]`, compiler/unit_pass.cpp): a unit that does not read, a term whose
// unit cannot match its equation, a function of a quantity with a unit, one parameter needing two
// units.
Diagnostic bad_unit(const Span& where, std::string_view signal, std::string_view expected);
Diagnostic unit_mismatch(const Span& where, std::string_view unit, std::string_view expected_unit, const Span& expected_at);
Diagnostic operation_unit_mismatch(const Span& where, std::string_view parameter, std::string_view unit,
                                   std::string_view other_unit, const Span& other_at);
Diagnostic function_of_unit(const Span& where, std::string_view function, std::string_view unit);
Diagnostic parameter_unit_conflict(const Span& where, std::string_view parameter, std::string_view unit,
                                   std::string_view other_unit, const Span& other_at);
Diagnostic unknown_pass(std::string_view name, std::string_view nearest, std::string_view passes);
Diagnostic integrate_option_invalid(std::string_view value);
Diagnostic no_signal(const Span& where);
// A parameter where only known quantities may stand (`what`: "the weights", "the truth of plot `f`").
Diagnostic parameter_not_allowed(const Span& where, std::string_view name, std::string_view what);
// `set weights = w` where `w` is no name of the model: most likely a column meant in quotes.
Diagnostic weights_unknown_name(const Span& where, std::string_view name, std::string_view nearest);
Diagnostic plot_argument_not_signal(const Span& where, std::string_view plot, std::string_view name, std::string_view nearest);
// A plotted function must depend on its argument alone (`quantity`: another signal, t, an integral ...).
Diagnostic plot_uses_other_quantity(const Span& where, std::string_view plot, std::string_view quantity, std::string_view argument);
Diagnostic plot_without_parameter(const Span& where, std::string_view plot);
Diagnostic plot_parameter_not_fitted(const Span& where, std::string_view plot, std::string_view parameter);
// [end of compiler-owned section]
// ---- simulation (compiler/explicit_form_pass.cpp, runtime/simulate/simulate.cpp)
Diagnostic simulate_integral(const Span& where, std::string_view term);
Diagnostic simulate_estimated_derivative(const Span& where, std::string_view term);
Diagnostic simulate_derivative_of_held_input(const Span& where, std::string_view signal, std::string_view hold, std::string_view written);
Diagnostic highest_derivative_nonlinear(const Span& where, std::string_view derivative, std::string_view how);
Diagnostic simulate_static_output(const Span& where, std::string_view output);
Diagnostic simulate_equation_count(const Span& where, std::size_t equations, std::size_t outputs);
Diagnostic highest_derivatives_unmatched(const Span& where, std::string_view derivatives);
Diagnostic simulate_initial_value_term(const Span& where, std::string_view term);

// ---- the fit's data (runtime/solve/drift_check.cpp) ------------------------------------------
// A warning: equation `number` (1-based), integrated `integrations` times, has `what` (e.g. "its
// known side `int(int(x))`") mostly a polynomial of degree `integrations` in t on `record`;
// `others` names further operations so dominated ("as is the operation of `k`"; may be empty).
Diagnostic drift_dominates(const Span& where, std::size_t number, int integrations, std::string_view what, std::string_view record, double share,
                           std::string_view others);
// ---- the fit's statistics (runtime/solve/fit.cpp) -----------------------------------------------
// Equation `number` (1-based) has a known side `known` that is zero on every row of `records` (the
// fitted records, named): every parameter would come out 0 with R^2 undefined.
Diagnostic known_side_zero(const Span& where, std::size_t number, std::string_view known, std::string_view records);
// A warning: the fit of `equations` ("equation 1", "equations 1 and 2") leaves `statistics` (from
// unrepresentable_statistics, joined) non-finite or beyond a double.
Diagnostic statistics_not_finite(const Span& where, std::string_view equations, std::string_view statistics);

}  // namespace sidc::diag
