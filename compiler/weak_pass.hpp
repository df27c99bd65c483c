// weak_pass: equations rewritten into the weak form (`set form = weak`, `sidc compile --form weak`).
//
// Relies on: normalize_pass (sum_k a_k op_k = known) and integrate_pass, which leaves weak requests
// alone. Guarantees: each such equation is multiplied by a smooth test function phi_j that vanishes,
// with its derivatives, at both ends of its subdomain, and integrated over the subdomain; every
// derivative of the data that an exact antiderivative can take off (integrate_pass's
// exact_antiderivative: y'' -> y', y^2*y' -> y^3/3, ...) is moved onto phi_j by parts,
// int(phi_j^(k) * F') = -int(phi_j^(k+1) * F), so `m*y'' + c*y' + k*y = x` becomes
// `m*phi_j''*y - c*phi_j'*y + k*phi_j*y = phi_j*x`. No boundary term and no integration constant
// appears, and no derivative of the data is estimated for these terms; what cannot be moved (a
// guarded y'^3, x'*y alone) stays as phi_j times the term, its derivatives estimated as in the
// derivative form. The thesis' integrated form is the special case of one subdomain from t0 with
// phi = 1 there, which is why it needs constants. The runtime places the subdomains and integrates
// (runtime/operators/test_functions.hpp). Pinned by tests/golden/weak/.
#pragma once

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"

namespace sidc {

ir::Model weak_pass(ir::Model model, Diagnostics& diagnostics);

// int(phi_j^(k) * s) as a sum of phi_j^(m) * g terms, derivatives moved onto phi_j where they can be.
ir::Sum weak_integrand(const ir::Sum& s, int k);

}  // namespace sidc
