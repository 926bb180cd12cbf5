// Internal to the diagnosis: a pole pair of a transfer function moved with its mode shape kept, as
// a structure's mode moves when its stiffness or damping changes (the path's antiresonances move
// with it), beside the pole_shift's factor D_from / D_to, which keeps the path's zeros.
//
// With R(s) the rational part of t (t = R e^{-s tau}), simple poles, and r the residue of R at
// the pair's upper member p (r = lim (s - p) R(s)), the mode's term is r / (s - p) + conj, that is
// A / (s^2 + 2 zeta wn s + wn^2) with A = 2 j Im(p) r: A (the mode shapes' product at the path's
// output and input) stays, so r' = r Im(p) / Im(p'), and the moved path is
//   R'(s) = R(s) + r' / (s - p') + conj(r') / (s - conj p') - r / (s - p) - conj(r) / (s - conj p),
// p' the pair (wn', zeta') moved to; the delay is kept. s in rad/s.
#pragma once

#include <complex>
#include <optional>

#include "fralab/core/tf.h"

namespace fralab::diag {

/// The residue of t's rational part at the upper member of its pair `pair` (nullopt: t does not
/// hold that pair as a simple pole within 1e-9, relative, or another pole sits on it).
std::optional<std::complex<double>> pair_residue(const Tf& t, const Root& pair);

/// R'(s) / R(s) at s: the factor the move applies to the path (r from pair_residue, R_s the
/// path's rational part at s).
std::complex<double> residue_move_factor(std::complex<double> R_s, const Root& from, const Root& to,
                                         std::complex<double> r, std::complex<double> s);

/// t with `from` moved to `to`, its mode shape kept, in factored form (every other pole's residue
/// and the constant term as they were; zeros found again). nullopt when t is improper, holds
/// a repeated pole, or does not hold `from`.
std::optional<Tf> moved_keeping_residue(const Tf& t, const Root& from, const Root& to);

}  // namespace fralab::diag
