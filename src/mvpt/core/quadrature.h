// Gauss-Legendre quadrature nodes and weights on [-1, 1].
#pragma once

#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

namespace mvpt {

/// Legendre polynomial P_l(x) and its derivative, by the three-term recurrence.
inline std::pair<double, double> legendre_pd(int l, double x) {
    if (l == 0) return {1.0, 0.0};
    if (l == 1) return {x, 1.0};
    double p_prev2 = 1.0, p_prev = x, p = 0.0, d_prev2 = 0.0, d_prev = 1.0, d = 0.0;
    for (int k = 2; k <= l; ++k) {
        p = ((2 * k - 1) * x * p_prev - (k - 1) * p_prev2) / k;
        d = d_prev2 + (2 * k - 1) * p_prev;
        p_prev2 = p_prev; p_prev = p;
        d_prev2 = d_prev; d_prev = d;
    }
    return {p, d};
}

/// n-point Gauss-Legendre rule: roots of P_n by Newton's method from Chebyshev
/// guesses, weights 2 / ((1 - x^2) P_n'(x)^2) [Abramowitz and Stegun 25.4.29].
inline void gauss_legendre(int n, std::vector<float> &nodes, std::vector<float> &weights) {
    if (n < 1) throw std::invalid_argument("gauss_legendre(): n must be >= 1");
    nodes.assign(n, 0.f);
    weights.assign(n, 0.f);
    for (int i = 0; i < (n + 1) / 2; ++i) {
        double x = -std::cos((2.0 * i + 1.0) / (2.0 * n) * 3.14159265358979323846);
        for (int it = 0;; ++it) {
            if (it > 20) throw std::runtime_error("gauss_legendre(): Newton iteration did not converge");
            auto [p, d] = legendre_pd(n, x);
            double step = p / d;
            x -= step;
            if (std::abs(step) <= 4.0 * std::abs(x) * 2.220446049250313e-16) break;
        }
        double d = legendre_pd(n, x).second;
        weights[i] = weights[n - 1 - i] = float(2.0 / ((1.0 - x * x) * d * d));
        nodes[i] = float(x);
        nodes[n - 1 - i] = float(-x);
    }
    if (n % 2 == 1) {
        double d = legendre_pd(n, 0.0).second;
        weights[n / 2] = float(2.0 / (d * d));
        nodes[n / 2] = 0.f;
    }
}

} // namespace mvpt
