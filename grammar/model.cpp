// The one instantiation of the grammar (calc9's expression.cpp): kept apart from the driver in
// parse.cpp because X3 instantiation dominates the build time.
#include "grammar/config.hpp"
#include "grammar/model_def.hpp"

namespace sidc::parser {

BOOST_SPIRIT_INSTANTIATE(statement_line_type, iterator_type, context_type)

}  // namespace sidc::parser
