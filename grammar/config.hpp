// The types the grammar is instantiated with (the calc9 layout): iterator, skipper, context.
//
// Relies on grammar/statement_scanner.hpp having cut the text into statements: the grammar only
// ever sees one statement, whose newlines are all continuations, so its skipper treats newlines
// like blanks. Guarantees: model.cpp instantiates the grammar for exactly context_type, which is
// what grammar/parse.cpp builds (phrase_parse with `white_space`, wrapped in
// x3::with<x3::error_handler_tag>(std::ref(handler))).
#pragma once

#include <boost/spirit/home/x3.hpp>
#include <functional>
#include <string>

#include "grammar/error_handler.hpp"

namespace sidc::parser {

namespace x3 = boost::spirit::x3;

using iterator_type = std::string::const_iterator;

// Skips blanks, line breaks (a statement's own continuation lines) and `#` comments.
struct white_space_parser : x3::parser<white_space_parser> {
  using attribute_type = x3::unused_type;
  static bool const has_attribute = false;

  template <typename Iterator, typename Context, typename RContext, typename Attribute>
  bool parse(Iterator& first, Iterator const& last, Context const&, RContext&, Attribute&) const {
    Iterator i = first;
    while (i != last) {
      const char c = *i;
      if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
        ++i;
      } else if (c == '#') {
        while (i != last && *i != '\n') ++i;
      } else {
        break;
      }
    }
    const bool skipped = i != first;
    first = i;
    return skipped;
  }
};

inline constexpr white_space_parser white_space{};

using skipper_type = white_space_parser;
using phrase_context_type = x3::phrase_parse_context<skipper_type>::type;
using error_handler_type = ErrorHandler<iterator_type>;
using context_type = x3::context<x3::error_handler_tag, std::reference_wrapper<error_handler_type>, phrase_context_type>;

}  // namespace sidc::parser
