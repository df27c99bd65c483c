// What the grammar records while it parses one statement: node spans and the failed expectation.
//
// Relies on X3's conventions (calc9): rules whose ID derives from x3::annotate_on_success call
// tag(); the outermost rule's ID derives from error_handler_base, whose on_error stores the first
// x3::expectation_failure (x.which() = the rule name, one of diag::expected, and x.where()).
// Guarantees: every tagged node gets id_first == id_last == its index in `positions`, whose entry
// is the node's [begin, end) byte range in the source (ParseResult::span reads it back); nothing
// here formats a message (grammar/parse.cpp turns the failure into a Diagnostic).
#pragma once

#include <boost/spirit/home/x3.hpp>
#include <boost/spirit/home/x3/support/ast/position_tagged.hpp>
#include <boost/spirit/home/x3/support/utility/error_reporting.hpp>
#include <cstddef>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace sidc::parser {

namespace x3 = boost::spirit::x3;

template <typename Iterator>
class ErrorHandler {
 public:
  struct Failure {
    Iterator where;     // where the expected thing should have begun (before white space)
    std::string which;  // what was expected, in words (diag::expected)
  };

  ErrorHandler(Iterator source_begin, std::vector<std::pair<std::size_t, std::size_t>>& positions)
      : source_begin_(source_begin), positions_(positions) {}

  // Called by x3::annotate_on_success; nodes that are no position_tagged (variants) are ignored:
  // every alternative of a variant is tagged by its own rule.
  template <typename Node>
  void tag(Node& node, Iterator first, Iterator last) {
    if constexpr (std::is_base_of_v<x3::position_tagged, Node>) {
      node.id_first = static_cast<int>(positions_.size());
      node.id_last = node.id_first;
      positions_.emplace_back(offset(first), offset(last));
    }
  }

  std::size_t offset(Iterator at) const { return static_cast<std::size_t>(at - source_begin_); }

  void expectation_failed(Iterator where, std::string which) {
    if (!failure_) failure_ = Failure{where, std::move(which)};
  }
  const std::optional<Failure>& failure() const { return failure_; }

 private:
  Iterator source_begin_;
  std::vector<std::pair<std::size_t, std::size_t>>& positions_;
  std::optional<Failure> failure_;
};

// The ID base of the outermost rule only: inner rules let expectation failures pass up to it, so
// that the statement fails as a whole and the driver resynchronises at the next one.
struct error_handler_base {
  template <typename Iterator, typename Exception, typename Context>
  x3::error_handler_result on_error(Iterator& /*first*/, Iterator const& /*last*/, Exception const& x,
                                    Context const& context) {
    x3::get<x3::error_handler_tag>(context).get().expectation_failed(x.where(), x.which());
    return x3::error_handler_result::fail;
  }
};

}  // namespace sidc::parser
