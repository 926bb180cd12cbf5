// Internal to the identify library: the Sanathanan-Koerner iteration of TFNS (see tfns.h, steps
// 1-3) on an orthonormal polynomial basis (Arnoldi on the weighted points). Not installed.
#pragma once

#include <vector>

#include "fit_data.h"
#include "fralab/identify/tfns.h"

namespace fralab::tfns_detail {

struct Sk {
  bool ok = false;
  Tf tf;
  int iterations = 0;
  double e_phi = 0;
  // sum W |g - N/D|^2 of the iterate returned (score's sse of its model with the delay)
  double sse = INFINITY;
};

// SK iteration at orders (n, m) on data g (delay already removed), frequencies scaled by ws
// (rad/s) inside. The first iteration's weights are W_i / |D0(s_i)|^2 with D0 = 1, or with D0 the
// polynomial of `den_start` (poles in rad/s, D0(0) = 1: vector fitting's poles). Up to
// o.max_iterations; the best iterate by its real error is returned. roots = false: its sse only
// (no root finding; Sk::tf empty).
Sk sk_fit(const Data& d, const std::vector<C>& g, int n, int m, double ws, const FitOptions& o,
          const std::vector<C>* den_start = nullptr, bool roots = true);

}  // namespace fralab::tfns_detail
