// Boost.Fusion views of the AST structs, so that X3 fills them member by member.
//
// Relies on grammar/ast.hpp. Guarantees: every struct the grammar builds from a sequence of two
// or more parsers is adapted here, in member order. Single-member structs (Identifier, Number,
// ModelName, Guard, ...) and ParameterItem/Setting are filled by semantic actions in
// grammar/model_def.hpp instead, because X3 1.74 does not reliably treat a one-element fusion
// sequence as its element. X3 1.74 knows only boost::optional; the traits at the end teach it
// std::optional (SignalItem::definition), using the extension points X3 itself specialises for
// boost::optional.
#pragma once

#include <boost/fusion/include/adapt_struct.hpp>
#include <boost/spirit/home/x3/support/traits/optional_traits.hpp>
#include <optional>

#include "grammar/ast.hpp"

BOOST_FUSION_ADAPT_STRUCT(sidc::ast::Variable, name, primes)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::Signed, sign, operand)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::Operation, op, operand)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::Expression, first, rest)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::Call, callee, arguments)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::Indexed, name, index)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::Comparison, lhs, op, rhs)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::SumOver, index, from, to, body)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::SignalItem, name, unit, hold, definition)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::SignalDeclaration, kind, signals)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::ConstantItem, name, value)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::ColumnBinding, signal, column)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::PlotStatement, name, argument, fitted, truth)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::DataStatement, path, bindings)
BOOST_FUSION_ADAPT_STRUCT(sidc::ast::Equation, lhs, rhs)

namespace boost::spirit::x3::traits {

template <typename T>
struct is_optional<std::optional<T>> : mpl::true_ {};

template <typename T>
struct optional_value<std::optional<T>> : mpl::identity<T> {};

template <typename T>
struct build_optional<std::optional<T>> {
  using type = std::optional<T>;
};

}  // namespace boost::spirit::x3::traits
