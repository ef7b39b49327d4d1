#include "hapticd/theory/twoport.hpp"

#include <array>

namespace hapticd::theory {
namespace {

// Port 1 takes its flow as input in Z and H, port 2 takes its flow as input in Z and G.
bool port1_flow_input(ImmittanceForm form) {
    return form == ImmittanceForm::impedance || form == ImmittanceForm::hybrid;
}
bool port2_flow_input(ImmittanceForm form) {
    return form == ImmittanceForm::impedance || form == ImmittanceForm::alternate_hybrid;
}
ImmittanceForm form_with(bool port1_flow_in, bool port2_flow_in) {
    if (port1_flow_in) {
        return port2_flow_in ? ImmittanceForm::impedance : ImmittanceForm::hybrid;
    }
    return port2_flow_in ? ImmittanceForm::alternate_hybrid : ImmittanceForm::admittance;
}

using Matrix = std::array<std::array<Complex, 2>, 2>;

// Principal pivot on index k: y_k and u_k swap places.
std::optional<Matrix> pivot(const Matrix& m, int k) {
    const int o = 1 - k;
    const Complex pivot_element = m[k][k];
    if (pivot_element == Complex(0.0, 0.0)) return std::nullopt;
    Matrix r;
    r[k][k] = 1.0 / pivot_element;
    r[k][o] = -m[k][o] / pivot_element;
    r[o][k] = m[o][k] / pivot_element;
    r[o][o] = m[o][o] - m[o][k] * m[k][o] / pivot_element;
    return r;
}

}  // namespace

std::string_view to_string(ImmittanceForm form) {
    switch (form) {
        case ImmittanceForm::impedance:
            return "impedance";
        case ImmittanceForm::admittance:
            return "admittance";
        case ImmittanceForm::hybrid:
            return "hybrid";
        case ImmittanceForm::alternate_hybrid:
            return "alternate_hybrid";
    }
    return "unknown";
}

std::optional<TwoPort> convert(const TwoPort& network, ImmittanceForm target) {
    std::optional<Matrix> m = Matrix{{{network.p11, network.p12}, {network.p21, network.p22}}};
    bool p1 = port1_flow_input(network.form);
    bool p2 = port2_flow_input(network.form);
    if (p1 != port1_flow_input(target)) {
        m = pivot(*m, 0);
        p1 = !p1;
    }
    if (m && p2 != port2_flow_input(target)) {
        m = pivot(*m, 1);
        p2 = !p2;
    }
    if (!m) return std::nullopt;
    return TwoPort{form_with(p1, p2), (*m)[0][0], (*m)[0][1], (*m)[1][0], (*m)[1][1]};
}

TwoPort dual(const TwoPort& network) {
    const ImmittanceForm dual_form =
        form_with(!port1_flow_input(network.form), !port2_flow_input(network.form));
    return TwoPort{dual_form, network.p11, -network.p12, -network.p21, network.p22};
}

}  // namespace hapticd::theory
