// The grammar of one `.sid` statement, in Spirit X3 (docs/language.md has the same grammar as
// EBNF; keep the two in step).
//
// Relies on grammar/statement_scanner.hpp: the input is one statement extent whose nesting is
// already known to be within parser::nesting_limit, so the recursion below (parentheses, unary
// signs, `^` chains) cannot exhaust the stack, and whose newlines are all continuations, so the
// skipper (config.hpp) treats them as blanks.
//
// Guarantees:
//   * every position_tagged node is annotated (rule IDs deriving from x3::annotate_on_success);
//   * after the keyword of a statement, or an operator, or an opening bracket, all parts are
//     expectation points (`>`), so a failure names what was missing (the rule names are the
//     phrases of diag::expected) and never backtracks exponentially;
//   * precedence levels follow calc9 (additive > multiplicative > unary > power > primary), but a
//     level with a single operand is not wrapped: an Operand never holds an Expression with an
//     empty `rest`, and the Expression of an equation side, argument, index, comparison side,
//     sum body or definition is the outermost level that has operators (or an Expression with an
//     empty `rest` holding a single operand). Parentheses leave no node of their own.
#pragma once

#include <boost/fusion/include/at_c.hpp>
#include <boost/fusion/include/std_pair.hpp>
#include <boost/range/iterator_range_core.hpp>
#include <boost/spirit/home/x3.hpp>
#include <boost/spirit/home/x3/support/utility/annotate_on_success.hpp>
#include <string>
#include <string_view>
#include <utility>

#include "grammar/ast.hpp"
#include "grammar/ast_adapted.hpp"
#include "grammar/config.hpp"
#include "diagnostics/model_catalogue.hpp"
#include "grammar/error_handler.hpp"
#include "grammar/model.hpp"

namespace sidc::parser {

namespace x3 = boost::spirit::x3;
namespace expected = diag::expected;

using x3::char_;
using x3::lexeme;
using x3::lit;
using x3::raw;

// ---- lexical pieces ------------------------------------------------------------------------------

// ASCII only (x3's character classes would hand bytes >= 0x80 to <cctype> as negative chars).
auto const name_start = char_('A', 'Z') | char_('a', 'z') | char_('_');
auto const name_char = name_start | char_('0', '9');
auto const digit = char_('0', '9');

// A whole word: `model` but not `models`.
inline auto keyword(char const* word) { return lexeme[lit(word) >> !name_char]; }

// A name: [A-Za-z_][A-Za-z0-9_]* that is no reserved word. One pass over the characters and one
// comparison with the reserved words: names are read several times per operand (X3 backtracks
// from `y(` and `y[` to `y`), so this is the grammar's hottest parser.
struct name_parser : x3::parser<name_parser> {
  using attribute_type = std::string;
  static bool const has_attribute = true;

  static bool is_start(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; }
  static bool is_part(char c) { return is_start(c) || (c >= '0' && c <= '9'); }

  template <typename Iterator>
  static bool is_reserved(Iterator first, Iterator last) {
    static constexpr std::string_view words[] = {"model", "input", "output", "param", "const", "data",
                                                 "set",   "and",   "sum",    "der",   "int",    "plot",  "against"};
    const auto length = static_cast<std::size_t>(last - first);
    if (length < 3 || length > 7) return false;
    const std::string_view word(&*first, length);
    for (std::string_view reserved : words)
      if (word == reserved) return true;
    return false;
  }

  template <typename Iterator, typename Context, typename RContext, typename Attribute>
  bool parse(Iterator& first, Iterator const& last, Context const& context, RContext&, Attribute& attr) const {
    x3::skip_over(first, last, context);
    Iterator i = first;
    if (i == last || !is_start(*i)) return false;
    ++i;
    while (i != last && is_part(*i)) ++i;
    if (is_reserved(first, i)) return false;
    x3::traits::move_to(first, i, attr);
    first = i;
    return true;
  }
};

inline constexpr name_parser name{};

// ---- rule declarations -----------------------------------------------------------------------------

// Named after what a failure would have expected (diag::expected), or after the construct when
// the rule is never an expectation point.
x3::rule<struct identifier_class, ast::Identifier> const identifier = "a name";
x3::rule<struct identifier_assembled_class, ast::Identifier> const identifier_assembled = "a name";
x3::rule<struct number_class, ast::Number> const number = "a number";
x3::rule<struct number_assembled_class, ast::Number> const number_assembled = "a number";
x3::rule<struct string_literal_class, std::string> const string_literal = "a quoted string";
x3::rule<struct closing_quote_class> const closing_quote = expected::closing_quote;
x3::rule<struct closing_parenthesis_class> const closing_parenthesis = expected::closing_parenthesis;
x3::rule<struct closing_bracket_class> const closing_bracket = expected::closing_bracket;
x3::rule<struct integer_class, int> const integer = expected::integer;
x3::rule<struct range_dots_class> const range_dots = expected::range_dots;

x3::rule<struct expression_class, ast::Expression> const expression = expected::expression;
x3::rule<struct expression_assembled_class, ast::Expression> const expression_assembled = expected::expression;
x3::rule<struct additive_operand_class, ast::Operand> const additive_operand = expected::expression;
x3::rule<struct additive_expression_class, ast::Expression> const additive_expression = expected::expression;
x3::rule<struct additive_operation_class, ast::Operation> const additive_operation = "`+` or `-` and a term";
x3::rule<struct term_class, ast::Operand> const term = expected::operand;
x3::rule<struct multiplicative_expression_class, ast::Expression> const multiplicative_expression = expected::operand;
x3::rule<struct multiplicative_operation_class, ast::Operation> const multiplicative_operation = "`*` or `/` and a factor";
x3::rule<struct unary_class, ast::Operand> const unary = expected::factor;
x3::rule<struct signed_operand_class, ast::Signed> const signed_operand = expected::factor;
x3::rule<struct power_class, ast::Operand> const power = expected::factor;
x3::rule<struct power_expression_class, ast::Expression> const power_expression = expected::factor;
x3::rule<struct power_operation_class, ast::Operation> const power_operation = "`^` and an exponent";
x3::rule<struct primary_class, ast::Operand> const primary = expected::factor;

x3::rule<struct variable_class, ast::Variable> const variable = "a variable such as `y'`";
x3::rule<struct builtin_callee_class, ast::Variable> const builtin_callee = "`der` or `int`";
x3::rule<struct builtin_callee_assembled_class, ast::Variable> const builtin_callee_assembled = "`der` or `int`";
x3::rule<struct call_parenthesis_class> const call_parenthesis = expected::call_parenthesis;
x3::rule<struct arguments_class, std::vector<ast::Expression>> const arguments = expected::expression;
x3::rule<struct builtin_call_class, ast::Call> const builtin_call = "a call of `der` or `int`";
x3::rule<struct call_class, ast::Call> const call = "a call such as `sin(y)`";
x3::rule<struct indexed_class, ast::Indexed> const indexed = "a family member such as `c[k]`";
x3::rule<struct comparison_operator_class, std::string> const comparison_operator = expected::comparison_operator;
x3::rule<struct comparison_class, ast::Comparison> const comparison = expected::comparison;
x3::rule<struct comparisons_class, std::vector<ast::Comparison>> const comparisons = expected::comparison;
x3::rule<struct guard_class, ast::Guard> const guard = "a guard such as `[y' <= 0]`";
x3::rule<struct guard_assembled_class, ast::Guard> const guard_assembled = "a guard such as `[y' <= 0]`";
x3::rule<struct sum_parenthesis_class> const sum_parenthesis = expected::sum_parenthesis;
x3::rule<struct sum_index_class, ast::Identifier> const sum_index = expected::sum_index;
x3::rule<struct sum_equals_class> const sum_equals = expected::sum_equals;
x3::rule<struct sum_comma_class> const sum_comma = expected::sum_comma;
x3::rule<struct sum_over_class, ast::SumOver> const sum_over = "a sum such as `sum(k = 1..6, c[k]*y^k)`";
x3::rule<struct parenthesised_class, ast::Operand> const parenthesised = "an expression in parentheses";

x3::rule<struct model_name_class, ast::Identifier> const model_name = expected::model_name;
x3::rule<struct model_statement_class, ast::ModelName> const model_statement = "a model statement";
x3::rule<struct model_statement_assembled_class, ast::ModelName> const model_statement_assembled = "a model statement";
x3::rule<struct signal_kind_class, std::string> const signal_kind = "`input` or `output`";
x3::rule<struct signal_name_class, ast::Identifier> const signal_name = expected::signal_name;
x3::rule<struct signal_item_class, ast::SignalItem> const signal_item = expected::signal_name;
x3::rule<struct signal_items_class, std::vector<ast::SignalItem>> const signal_items = expected::signal_name;
x3::rule<struct signal_declaration_class, ast::SignalDeclaration> const signal_declaration = "a signal declaration";
x3::rule<struct unit_text_class, ast::UnitText> const unit_text = "a unit";
x3::rule<struct unit_text_assembled_class, ast::UnitText> const unit_text_assembled = "a unit";
x3::rule<struct parameter_name_class, ast::Identifier> const parameter_name = expected::parameter_name;
x3::rule<struct family_range_class, std::pair<int, int>> const family_range = "a range such as `[1..6]`";
x3::rule<struct parameter_item_class, ast::ParameterItem> const parameter_item = expected::parameter_name;
x3::rule<struct parameter_item_assembled_class, ast::ParameterItem> const parameter_item_assembled = expected::parameter_name;
x3::rule<struct parameter_items_class, std::vector<ast::ParameterItem>> const parameter_items = expected::parameter_name;
x3::rule<struct parameter_declaration_class, ast::ParameterDeclaration> const parameter_declaration = "a parameter declaration";
x3::rule<struct parameter_declaration_assembled_class, ast::ParameterDeclaration> const parameter_declaration_assembled = "a parameter declaration";
x3::rule<struct constant_name_class, ast::Identifier> const constant_name = expected::constant_name;
x3::rule<struct constant_equals_class> const constant_equals = expected::constant_equals;
x3::rule<struct constant_item_class, ast::ConstantItem> const constant_item = expected::constant_name;
x3::rule<struct constant_items_class, std::vector<ast::ConstantItem>> const constant_items = expected::constant_name;
x3::rule<struct constant_declaration_class, ast::ConstantDeclaration> const constant_declaration = "a constant declaration";
x3::rule<struct constant_declaration_assembled_class, ast::ConstantDeclaration> const constant_declaration_assembled = "a constant declaration";
x3::rule<struct file_name_class, std::string> const file_name = expected::file_name;
x3::rule<struct binding_signal_class, ast::Variable> const binding_signal = expected::binding_signal;
x3::rule<struct binding_equals_class> const binding_equals = expected::binding_equals;
x3::rule<struct column_name_class, std::string> const column_name = expected::column_name;
x3::rule<struct column_binding_class, ast::ColumnBinding> const column_binding = expected::binding_signal;
x3::rule<struct column_bindings_class, std::vector<ast::ColumnBinding>> const column_bindings = expected::binding_signal;
x3::rule<struct data_statement_class, ast::DataStatement> const data_statement = "a data statement";
x3::rule<struct setting_name_class, ast::Identifier> const setting_name = expected::setting_name;
x3::rule<struct setting_equals_class> const setting_equals = expected::setting_equals;
x3::rule<struct setting_value_class, boost::iterator_range<iterator_type>> const setting_value = expected::setting_value;
x3::rule<struct setting_class, ast::Setting> const setting = "a setting";
x3::rule<struct weights_value_class, ast::WeightsValue> const weights_value = expected::weights_value;
x3::rule<struct weights_setting_class, ast::WeightsSetting> const weights_setting = "a weights setting";
x3::rule<struct weights_setting_assembled_class, ast::WeightsSetting> const weights_setting_assembled = "a weights setting";
x3::rule<struct plot_name_class, ast::Identifier> const plot_name = expected::plot_name;
x3::rule<struct plot_parenthesis_class> const plot_parenthesis = expected::plot_parenthesis;
x3::rule<struct plot_argument_class, ast::Variable> const plot_argument = expected::plot_argument;
x3::rule<struct plot_equals_class> const plot_equals = expected::plot_equals;
x3::rule<struct plot_statement_class, ast::PlotStatement> const plot_statement = "a plot statement";
x3::rule<struct setting_assembled_class, ast::Setting> const setting_assembled = "a setting";
x3::rule<struct equation_equals_class> const equation_equals = expected::equation_equals;
x3::rule<struct equation_class, ast::Equation> const equation = "an equation";
x3::rule<struct statement_class, ast::Statement> const statement = expected::statement;
x3::rule<struct end_of_statement_class> const end_of_statement = expected::end_of_statement;
statement_line_type const statement_line = expected::statement;

// ---- semantic actions ------------------------------------------------------------------------------

// Text of a raw[] match into a node's string member.
auto const assign_name = [](auto& ctx) { x3::_val(ctx).name = std::move(x3::_attr(ctx)); };
auto const assign_number = [](auto& ctx) {
  auto const& text = x3::_attr(ctx);
  x3::_val(ctx).text.assign(text.begin(), text.end());
};

// `der`/`int` as the callee of a Call; its Identifier is tagged here since no rule builds it.
auto const assign_builtin_callee = [](auto& ctx) {
  auto const& text = x3::_attr(ctx);
  ast::Variable& callee = x3::_val(ctx);
  callee.name.name.assign(text.begin(), text.end());
  x3::get<x3::error_handler_tag>(ctx).get().tag(callee.name, text.begin(), text.end());
};

// A precedence level with a single operand is that operand (see the file comment).
auto const collapse = [](auto& ctx) {
  ast::Expression& level = x3::_attr(ctx);
  if (level.rest.empty())
    x3::_val(ctx) = std::move(level.first);
  else
    x3::_val(ctx) = std::move(level);
};

// The outermost level with operators, or an Expression holding the single operand.
auto const as_expression = [](auto& ctx) {
  ast::Operand& operand = x3::_attr(ctx);
  ast::Expression& result = x3::_val(ctx);
  if (auto* level = boost::get<x3::forward_ast<ast::Expression>>(&operand.get())) {
    result = std::move(level->get());
  } else {
    result.first = std::move(operand);
    result.rest.clear();
  }
};

auto const assign_model_name = [](auto& ctx) { x3::_val(ctx).name = std::move(x3::_attr(ctx)); };
auto const assign_conditions = [](auto& ctx) { x3::_val(ctx).conditions = std::move(x3::_attr(ctx)); };
auto const assign_parameters = [](auto& ctx) { x3::_val(ctx).parameters = std::move(x3::_attr(ctx)); };
auto const assign_constants = [](auto& ctx) { x3::_val(ctx).constants = std::move(x3::_attr(ctx)); };

auto const assign_parameter_item = [](auto& ctx) {
  auto& parts = x3::_attr(ctx);
  ast::ParameterItem& item = x3::_val(ctx);
  item.name = std::move(boost::fusion::at_c<0>(parts));
  if (auto const& range = boost::fusion::at_c<1>(parts)) {
    item.from = range->first;
    item.to = range->second;
  }
  if (auto& guess = boost::fusion::at_c<2>(parts)) item.guess = std::move(*guess);
};

// The value is the raw text after `=`, without the comment and trailing blanks.
auto const assign_setting = [](auto& ctx) {
  auto& parts = x3::_attr(ctx);
  ast::Setting& result = x3::_val(ctx);
  result.key = std::move(boost::fusion::at_c<0>(parts));
  auto const& value = boost::fusion::at_c<1>(parts);
  auto end = value.end();
  while (end != value.begin() && (*(end - 1) == ' ' || *(end - 1) == '\t' || *(end - 1) == '\r')) --end;
  result.value.assign(value.begin(), end);
  result.value_offset = x3::get<x3::error_handler_tag>(ctx).get().offset(value.begin());
};

// The unit's text between the brackets, and where it starts (for a caret inside it).
auto const assign_unit_text = [](auto& ctx) {
  auto const& text = x3::_attr(ctx);
  ast::UnitText& result = x3::_val(ctx);
  result.text.assign(text.begin(), text.end());
  result.offset = x3::get<x3::error_handler_tag>(ctx).get().offset(text.begin());
};

auto const assign_weights = [](auto& ctx) { x3::_val(ctx).value = std::move(x3::_attr(ctx)); };

// ---- lexical rules -------------------------------------------------------------------------------

auto const identifier_assembled_def = name[assign_name];

// 3, 0.005, .5, 5., 1e-3, 2.5E+4. Range bounds (`1..6`) never reach this rule: they are
// `integer`s, read only where a range is allowed.
auto const number_assembled_def =
    raw[lexeme[((+digit >> -(lit('.') >> *digit)) | (lit('.') >> +digit)) >>
               -((lit('e') | lit('E')) >> -(lit('+') | lit('-')) >> +digit)]][assign_number];

auto const string_literal_def = lexeme[lit('"') >> *(char_ - '"') > closing_quote];
auto const closing_quote_def = lit('"');
auto const closing_parenthesis_def = lit(')');
auto const closing_bracket_def = lit(']');
auto const integer_def = x3::int_;
auto const range_dots_def = lit("..");

// ---- expressions ---------------------------------------------------------------------------------

auto const expression_assembled_def = additive_operand[as_expression];
auto const additive_operand_def = additive_expression[collapse];
auto const additive_expression_def = term >> *additive_operation;
auto const additive_operation_def = (char_('+') | char_('-')) > term;
auto const term_def = multiplicative_expression[collapse];
auto const multiplicative_expression_def = unary >> *multiplicative_operation;
auto const multiplicative_operation_def = (char_('*') | char_('/')) > unary;
// -y^2 is -(y^2); y^-1 is allowed.
auto const unary_def = signed_operand | power;
auto const signed_operand_def = (char_('-') | char_('+')) > unary;
auto const power_def = power_expression[collapse];
// Right associative: y^2^3 is y^(2^3), the exponent being a unary (a signed power).
auto const power_expression_def = primary >> x3::repeat(0, 1)[power_operation];
auto const power_operation_def = char_('^') > unary;

// Names first: they are the most frequent operands, and `sum`, `der`, `int` are no names.
auto const primary_def = number | call | indexed | variable | sum_over | builtin_call | guard | parenthesised;

auto const variable_def = lexeme[identifier >> *char_('\'')];
auto const builtin_callee_assembled_def = raw[lexeme[(lit("der") | lit("int")) >> !name_char]][assign_builtin_callee];
auto const call_parenthesis_def = lit('(');
auto const arguments_def = expression >> *(lit(',') > expression);
auto const builtin_call_def = builtin_callee > call_parenthesis > arguments > closing_parenthesis;
// The callee may carry primes: y'(0) is the initial value of y'.
auto const call_def = variable >> lit('(') > arguments > closing_parenthesis;
auto const indexed_def = identifier >> lit('[') > expression > closing_bracket;

// `<=`/`>=` before `<`/`>`.
auto const comparison_operator_def = x3::string("<=") | x3::string(">=") | x3::string("<") | x3::string(">");
auto const comparison_def = expression > comparison_operator > expression;
auto const comparisons_def = comparison >> *(keyword("and") > comparison);
auto const guard_assembled_def = (lit('[') > comparisons > closing_bracket)[assign_conditions];

auto const sum_parenthesis_def = lit('(');
auto const sum_index_def = identifier;
auto const sum_equals_def = lit('=');
auto const sum_comma_def = lit(',');
auto const sum_over_def = keyword("sum") > sum_parenthesis > sum_index > sum_equals > integer > range_dots >
                          integer > sum_comma > expression > closing_parenthesis;

auto const parenthesised_def = lit('(') > additive_operand > closing_parenthesis;

// ---- statements ----------------------------------------------------------------------------------

auto const model_name_def = identifier;
auto const model_statement_assembled_def = (keyword("model") > model_name)[assign_model_name];

auto const signal_kind_def = raw[lexeme[(lit("input") | lit("output")) >> !name_char]];
auto const signal_name_def = identifier;
// `input x = 60*sin(4*pi*t)`: an input given as an expression of t; `input x held`: how a recorded
// input was held between its samples.
// `output theta [rad]`: the unit, read by the compiler (ir/units.hpp).
auto const unit_text_assembled_def = (lit('[') > raw[lexeme[*(char_ - ']')]] > closing_bracket)[assign_unit_text];
auto const signal_item_def = signal_name >> -unit_text >> -identifier >> -(lit('=') > expression);
auto const signal_items_def = signal_item >> *(lit(',') > signal_item);
auto const signal_declaration_def = signal_kind > signal_items;

auto const parameter_name_def = identifier;
auto const family_range_def = lit('[') > integer > range_dots > integer > closing_bracket;
auto const parameter_item_assembled_def = (parameter_name >> -family_range >> -(lit('=') > expression))[assign_parameter_item];
auto const parameter_items_def = parameter_item >> *(lit(',') > parameter_item);
auto const parameter_declaration_assembled_def = (keyword("param") > parameter_items)[assign_parameters];

auto const constant_name_def = identifier;
auto const constant_equals_def = lit('=');
auto const constant_item_def = constant_name > constant_equals > expression;
auto const constant_items_def = constant_item >> *(lit(',') > constant_item);
auto const constant_declaration_assembled_def = (keyword("const") > constant_items)[assign_constants];

auto const file_name_def = string_literal;
// `y'` binds an exact derivative recorded with the output (compared, never fitted).
auto const binding_signal_def = lexeme[identifier >> *char_('\'')];
auto const binding_equals_def = lit('=');
// A column named by a plain word may be any word, reserved or not: it names a CSV column.
auto const column_name_def = string_literal | raw[lexeme[name_start >> *name_char]];
auto const column_binding_def = binding_signal > binding_equals > column_name;
auto const column_bindings_def = column_binding >> *(lit(',') > column_binding);
auto const data_statement_def = keyword("data") > file_name > -(lit('(') > column_bindings > closing_parenthesis);

auto const setting_name_def = identifier;
auto const setting_equals_def = lit('=');
// The scanner ended the statement at the line's end or `;`; the comment is not part of the value.
auto const setting_value_def = raw[lexeme[+(char_ - '#')]];
auto const setting_assembled_def = (keyword("set") > setting_name > setting_equals > setting_value)[assign_setting];
// `weights` alone takes an expression, so it has its own rule, tried before the generic one.
auto const weights_value_def = string_literal | expression;
auto const weights_setting_assembled_def =
    (keyword("set") >> keyword("weights") > setting_equals > weights_value)[assign_weights];

auto const plot_name_def = identifier;
auto const plot_parenthesis_def = lit('(');
auto const plot_argument_def = lexeme[identifier >> *char_('\'')];
auto const plot_equals_def = lit('=');
auto const plot_statement_def = keyword("plot") > plot_name > plot_parenthesis > plot_argument > closing_parenthesis >
                                plot_equals > expression > -(keyword("against") > expression);

auto const equation_equals_def = lit('=');
auto const equation_def = expression > equation_equals > expression;

auto const statement_def = model_statement | signal_declaration | parameter_declaration | constant_declaration |
                           data_statement | weights_setting | setting | plot_statement | equation;
auto const end_of_statement_def = x3::eoi;
auto const statement_line_def = x3::expect[statement] > end_of_statement;

// ---- annotated faces of the rules with semantic actions ------------------------------------------

// X3 1.74 hands on_success no attribute when a rule's definition holds a semantic action, so each
// such rule is split: `x_assembled` runs the action, and `x` (annotated) only refers to it.
auto const identifier_def = identifier_assembled;
auto const number_def = number_assembled;
auto const builtin_callee_def = builtin_callee_assembled;
auto const guard_def = guard_assembled;
auto const expression_def = expression_assembled;
auto const model_statement_def = model_statement_assembled;
auto const parameter_item_def = parameter_item_assembled;
auto const parameter_declaration_def = parameter_declaration_assembled;
auto const constant_declaration_def = constant_declaration_assembled;
auto const setting_def = setting_assembled;
auto const weights_setting_def = weights_setting_assembled;
auto const unit_text_def = unit_text_assembled;

// (Boost.Preprocessor takes at most 64 arguments per macro call.)
BOOST_SPIRIT_DEFINE(identifier, number, string_literal, closing_quote, closing_parenthesis, closing_bracket, integer,
                    range_dots)
BOOST_SPIRIT_DEFINE(expression, additive_operand, additive_expression, additive_operation, term,
                    multiplicative_expression, multiplicative_operation, unary, signed_operand, power,
                    power_expression, power_operation, primary, variable, builtin_callee, call_parenthesis,
                    arguments, builtin_call, call, indexed, comparison_operator, comparison, comparisons, guard,
                    sum_parenthesis, sum_index, sum_equals, sum_comma, sum_over, parenthesised)
BOOST_SPIRIT_DEFINE(identifier_assembled, number_assembled, builtin_callee_assembled, guard_assembled,
                    expression_assembled, model_statement_assembled, parameter_item_assembled,
                    parameter_declaration_assembled, constant_declaration_assembled, setting_assembled,
                    weights_setting_assembled, unit_text_assembled)
BOOST_SPIRIT_DEFINE(model_name, model_statement, signal_kind, signal_name, signal_item, signal_items,
                    signal_declaration, parameter_name, family_range, parameter_item, parameter_items,
                    parameter_declaration, constant_name, constant_equals, constant_item, constant_items,
                    constant_declaration, file_name, binding_signal, binding_equals, column_name, column_binding,
                    column_bindings, data_statement, setting_name, setting_equals, setting_value, setting,
                    equation_equals, equation, statement, end_of_statement, statement_line)
BOOST_SPIRIT_DEFINE(unit_text, weights_value, weights_setting, plot_name, plot_parenthesis, plot_argument, plot_equals,
                    plot_statement)

// ---- annotation and error handling -----------------------------------------------------------------

// Every rule that builds a position_tagged node records its span.
struct identifier_class : x3::annotate_on_success {};
struct number_class : x3::annotate_on_success {};
struct expression_class : x3::annotate_on_success {};
struct additive_expression_class : x3::annotate_on_success {};
struct additive_operation_class : x3::annotate_on_success {};
struct multiplicative_expression_class : x3::annotate_on_success {};
struct multiplicative_operation_class : x3::annotate_on_success {};
struct signed_operand_class : x3::annotate_on_success {};
struct power_expression_class : x3::annotate_on_success {};
struct power_operation_class : x3::annotate_on_success {};
struct variable_class : x3::annotate_on_success {};
struct builtin_callee_class : x3::annotate_on_success {};
struct builtin_call_class : x3::annotate_on_success {};
struct call_class : x3::annotate_on_success {};
struct indexed_class : x3::annotate_on_success {};
struct comparison_class : x3::annotate_on_success {};
struct guard_class : x3::annotate_on_success {};
struct sum_over_class : x3::annotate_on_success {};
struct model_statement_class : x3::annotate_on_success {};
struct signal_item_class : x3::annotate_on_success {};
struct unit_text_class : x3::annotate_on_success {};
struct signal_declaration_class : x3::annotate_on_success {};
struct parameter_item_class : x3::annotate_on_success {};
struct parameter_declaration_class : x3::annotate_on_success {};
struct constant_item_class : x3::annotate_on_success {};
struct constant_declaration_class : x3::annotate_on_success {};
struct column_binding_class : x3::annotate_on_success {};
struct binding_signal_class : x3::annotate_on_success {};
struct data_statement_class : x3::annotate_on_success {};
struct setting_class : x3::annotate_on_success {};
struct weights_setting_class : x3::annotate_on_success {};
struct plot_argument_class : x3::annotate_on_success {};
struct plot_statement_class : x3::annotate_on_success {};
struct equation_class : x3::annotate_on_success {};

// Only the outermost rule handles errors.
struct statement_line_class : error_handler_base {};

}  // namespace sidc::parser

namespace sidc {

parser::statement_line_type const& statement_line() { return parser::statement_line; }

}  // namespace sidc
