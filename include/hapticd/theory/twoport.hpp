// Two-port immittance matrices, (1)-(4), and conversion between the four forms.
//
// Every form relates the efforts (F1, F2) and flows (v1, -v2) of one two-port; the
// negative sign on v2 follows the paper's network convention. A form is named by
// which port variables are its inputs:
//   impedance Z        (1): [F1, F2]  = Z [v1, -v2]
//   admittance Y       (2): [v1, -v2] = Y [F1, F2]
//   hybrid H           (3): [F1, -v2] = H [v1, F2]
//   alternate hybrid G (4): [v1, F2]  = G [F1, -v2]
// Converting between forms swaps input and output at one or both ports, which is a
// principal pivot of the matrix on that port's index.
#pragma once

#include <optional>
#include <string_view>

#include "hapticd/theory/unit_circle.hpp"

namespace hapticd::theory {

enum class ImmittanceForm { impedance, admittance, hybrid, alternate_hybrid };

std::string_view to_string(ImmittanceForm form);

/// A 2x2 immittance matrix evaluated at one frequency.
struct TwoPort {
    ImmittanceForm form = ImmittanceForm::hybrid;
    Complex p11, p12, p21, p22;
};

/// The same network in another immittance form, or nullopt when that form does not
/// exist for it (the pivot element is zero, e.g. the impedance form of (14)).
std::optional<TwoPort> convert(const TwoPort& network, ImmittanceForm target);

/// The dual network (Definition 6): efforts and flows swap roles. A hybrid matrix maps
/// to an alternate hybrid one and an impedance matrix to an admittance one, with the
/// off-diagonal terms negated by the -v2 convention, as between (14) and (28).
TwoPort dual(const TwoPort& network);

}  // namespace hapticd::theory
