// The multisine analyses' shared line statistics (pair_analyzer.cc, orthogonal_multisine.cc):
// which lines a period's spectrum holds, the noise about a line's period values, and the points'
// common fields. Lines are FFT bins k of a period of P samples (k Hz = k fs / P).
#pragma once

#include <complex>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "fralab/core/block.h"

namespace fralab::analyze_detail {

// An orthogonal multisine's lines: unique, ascending, within 1..P/2-1 (what a period resolves).
inline std::vector<int> orthogonal_lines(const StatusEvent& st) {
  std::set<int> uniq;
  for (int k : st.lines)
    if (k >= 1 && k < st.period_samples / 2) uniq.insert(k);
  return {uniq.begin(), uniq.end()};
}

// The nearest line no input excites on each side of line k (at most two), within 1..P/2-1.
inline std::vector<int> unexcited_neighbours(const std::vector<bool>& excited, int k, int P) {
  std::vector<int> out;
  for (int dir : {-1, 1})
    for (int kk = k + dir; kk >= 1 && kk < P / 2; kk += dir)
      if (!excited[kk]) {
        out.push_back(kk);
        break;
      }
  return out;
}

// sum_p |z_p - mean_p z|^2 over the M periods: the spread of a line's period values about their
// mean (a periodic part, distortion or the response itself, cancels in it).
template <class Z>
double period_spread(int M, const Z& z) {
  std::complex<double> zm = 0;
  for (int p = 0; p < M; ++p) zm += z(p);
  zm /= double(M);
  double s = 0;
  for (int p = 0; p < M; ++p) s += std::norm(z(p) - zm);
  return s;
}

// A point's sigma, > 0 as the contract needs: noise-free periods repeat exactly and spread by 0.
inline double positive_sigma(double sigma, double mag) {
  return sigma > 0 ? sigma : 1e-300 + 1e-15 * mag;
}

// The status's first excited input and its amplitude ("", 0 for none).
inline std::pair<std::string, double> first_excited(const StatusEvent& st) {
  for (size_t i = 0; i < st.inputs.size() && i < st.amplitudes.size(); ++i) {
    if (st.amplitudes[i] > 0.0) return {st.inputs[i], st.amplitudes[i]};
  }
  return {"", 0.0};
}

}  // namespace fralab::analyze_detail
