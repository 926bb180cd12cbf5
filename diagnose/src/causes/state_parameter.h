// state_parameter: one entry of the simulation's state model (plant/state_space.h) changed. A
// diagonal entry of A is a state's own rate (-1 / its time constant, 1/s), another entry of A a
// coupling between states, an entry of B how an input drives a state, of C how a state shows at an
// output. The entry moves every pole, zero and gain of every path the state reaches, so it is
// fitted once over every pair (stage 3a, stages/states.cc) and is one finding.
//
// Parameters (docs/formats.md §15): `from`, `to` (the entry's value in the simulation and as
// fitted; A's in 1/s, B's and C's in the state's units per input or output unit), `row` and `col`
// (1-based), for a diagonal entry of A `time_constant_from_s` and `time_constant_to_s`; text
// parameters `matrix` ("A", "B" or "C") and `state`, and `input` or `output` for B and C (the
// names of the state model).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "cause.h"
#include "fralab/plant/state_space.h"

namespace fralab::diag {

/// An entry of A, B or C (row, col 0-based; of D only as a named parameter sets it, never a
/// candidate of its own); 'P', the owner's named parameter `row`
/// (StateSpace::parameters, valued by the parameter, setting its entries); or what the
/// simulation lacks: 'U', a first-order
/// lag (a state) before input `col` (the column of B and D it drives), 'Y', one after output
/// `row`, each valued by its time constant (s); 'I', a delay added to input `col`'s, 'O', one
/// added to output `row`'s, each valued by the delay (s). An added lag or delay of 0 is absent,
/// the simulation's value.
struct StateEntry {
  char matrix = 'A';
  int row = 0, col = 0;
  /// A lag the simulation lacks (a state it adds).
  bool lag() const { return matrix == 'U' || matrix == 'Y'; }
  /// A delay the simulation lacks.
  bool delay() const { return matrix == 'I' || matrix == 'O'; }
  /// Either: not an entry of the simulation's matrices, valued from 0.
  bool added() const { return lag() || delay(); }
  /// At an input ('U', 'I'; else at an output, or an entry of the matrices).
  bool at_input() const { return matrix == 'U' || matrix == 'I'; }
  /// A named parameter.
  bool named() const { return matrix == 'P'; }
};

/// Whether a and b set a common entry of A, B or C (an entry and a named parameter setting it,
/// two parameters setting one entry, or the same entry): their moves do not add.
bool overlap(const StateSpace& ss, const StateEntry& a, const StateEntry& b);

/// The entry's value in `ss` (0 for an added lag or delay; a named parameter's value).
double entry_value(const StateSpace& ss, const StateEntry& e);
/// `ss` with the entry set to v. An added lag of time constant v > 0 is a new last state x_l:
/// before input j, x_l' = (u_j - x_l) / v driving what u_j drove (B's and D's column j); after
/// output i, x_l' = (y_i - x_l) / v read as output i. An added delay v > 0 is added to the
/// input's or the output's delay. Apply the entries of A, B and C first.
StateSpace with_entry(const StateSpace& ss, const StateEntry& e, double v);
/// Every path of `ss` (outputs x inputs; nullopt: zero), delays included; nullopt as a whole when
/// a path cannot be factored (an unstable or degenerate entry: not a candidate value).
std::optional<std::vector<std::vector<std::optional<Tf>>>> state_paths(const StateSpace& ss);

/// A finding of the entry moved from its value in `ss` to `to`, scope plant, over `pairs`: an
/// entry's matrix, row, col and state; a named parameter's name, units and the states its
/// entries set.
Finding state_parameter_finding(const StateSpace& ss, const StateEntry& e, double to,
                                const std::vector<std::string>& pairs);

}  // namespace fralab::diag
