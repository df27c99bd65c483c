#include "ir/explicit_form.hpp"

namespace sidc {

std::size_t ExplicitForm::state_size() const {
  std::size_t n = 0;
  for (const auto& o : outputs) n += static_cast<std::size_t>(o.order);
  return n;
}

}  // namespace sidc
