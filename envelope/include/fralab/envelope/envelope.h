// An engine across its operating points (the report's Section III): the points' results (each
// measured, identified and diagnosed into DIR/<point>/ as `fralab run` does: lab/envelope.h runs
// the campaign) read back and joined:
//
// - States across paths and points. Within a point the states are the transfer matrix's poles
//   from one pole set over the paths (transfer_matrix.json's `common_pole_set`, else its clustered
//   `common_poles`), each with the paths that need it and its scope (every path: a plant state;
//   the paths into one output: that sensor; from one input: that actuator). Across points a
//   state's pole is followed into a track: points in the scheduling variable's order, each state
//   joined to the track of its kind (real or pair) whose last root is nearest on a log scale,
//   within a factor `track_ratio`, and that shares a path with it (a change of label, sensor T5 to
//   plant, costs the whole factor: the spool's and the thermocouple's time constants cross
//   between points); else it starts a track. Per
//   point a track gives its root (time constant 1/|p| in s for a real pole; wn in rad/s and zeta
//   for a pair), the spread over its member paths' own fits (their nearest root of the kind, within
//   a factor 1.5) and their median relative sigma. A track absent at some points, or not monotone
//   in the scheduling variable (successive steps of opposite sign, each larger than the two
//   points' sigmas together), is flagged with the figures.
// - Findings across points. A finding is keyed by cause, scope, input and output; per point its
//   primary parameter (the key of its `intervals`: the 1-sigma interval; a missing side mirrored)
//   and the simulation's value where the cause has one (`from_*`). A law in the scheduling
//   variable x is chosen among constant (a), linear (a + b x) and power (a x^b, positive values)
//   by weighted least squares and the criterion chi^2 + k ln(n) (k parameters, n points); the
//   slope b with its sigma (the covariance scaled by chi^2/dof when above 1). A finding present at
//   some points only says which.
// - Slow states, as the report's Section III tables give them ("Spool Inertia Time Constants":
//   the time constants averaged over the transfer functions, with their range). The states above
//   follow one pole set; where the engine's paths hold one state at different roots (the J85's
//   spool: 0.27-0.86 s over its paths at 85 %), they split it. Here each path's slowest real
//   pole in its own fit is taken; per point an output's value is the mean of its paths'. The
//   plant's state joins the outputs whose values agree within a factor `slow_ratio` at every
//   point (pairwise, starting from the output with the most paths; at least two outputs). Every
//   other output with paths is a state of its own: `sensor <output>` when its value is slower
//   than the plant's at every point (a lag in series: the T5 thermocouple), else `output
//   <output>` (its paths' slowest root is faster than the plant's: P5's, as the report also
//   notes). Per point a state gives the mean time constant over its member paths, their range
//   and count, the standard error of the mean, and the inverse of the poles' mean (the report
//   averages time constants for the spool, poles for the thermocouple at 85 %); a sensor's path
//   whose slowest root is not slower than the plant's at that point does not show the sensor and is
//   left out, said in `without` (the J85's Wf:T5 at 95 %, the report's "missing from the 95 percent
//   model"). Flags as for the states above, steps compared with the standard errors.
//
// Units: rad/s, seconds; x in the operating point's units (speed_pct: % N/Nmax).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fralab/core/json_util.h"
#include "fralab/diagnose/diagnose.h"

namespace fralab {

struct EnvelopeOptions {
  std::string schedule_by = "speed_pct";  // a key of the models' operating_point
  double track_ratio = 2.5;               // a track's root moves by less than this between points
  /// Outputs whose slowest roots agree within this factor at every point share the plant's slow
  /// state. 1.8: on the J85 the outputs N, P3 and DPP3 agree within 1.7, P5 and T5 differ from N
  /// by 2.1 or more at every point.
  double slow_ratio = 1.8;
  /// Throws InputError naming the bad option.
  void validate() const;
};

// One operating point's results, as read back from its folder.
struct EnvelopePoint {
  std::string name;        // its folder under DIR
  double x = 0;            // the scheduling variable
  std::string simulation;  // the simulation's spec ("" when not known)
  Json transfer_matrix;    // DIR/<point>/measure/transfer_matrix.json (null: none)
  Json diagnosis;          // DIR/<point>/diagnosis.json (null: none)
};

struct TrackValue {
  std::string point;
  double x = 0;
  bool pair = false;
  double value = 0;                     // tau_s (real) or wn_rad_s (pair)
  double zeta = 0;                      // pairs
  double spread_lo = 0, spread_hi = 0;  // the member paths' own roots, same units (= value: none)
  double rel_sigma = -1;                // median over those paths (< 0: unknown)
  std::string scope, where;
  std::vector<std::string> paths;
};

struct StateTrack {
  std::string label;  // "plant", "sensor T5", "actuator A8", "path Wf:N"
  bool pair = false;
  std::vector<TrackValue> values;  // in x order
  bool at_every_point = true;
  bool monotone = true;
  std::string flags;  // the figures behind a flag ("" when none)
};

struct SlowState {
  std::string label;                 // "plant", "sensor <output>", "output <output>"
  std::vector<std::string> outputs;  // the outputs whose paths hold it
  struct Value {
    std::string point;
    double x = 0;
    double tau_s = 0;                  // the mean of the member paths' time constants, s
    double lo = 0, hi = 0;             // their range, s
    double sem = 0;                    // the standard error of the mean (0 for one path), s
    double tau_of_mean_pole_s = 0;     // 1 / (the mean of the paths' poles 1/tau), s
    std::vector<std::string> paths;    // the member paths, "input:output"
    std::vector<std::string> without;  // a sensor's paths left out (not slower than the plant)
  };
  std::vector<Value> values;  // in x order
  bool at_every_point = true;
  bool monotone = true;
  std::string flags;  // "" when none
};

struct FindingLaw {
  std::string cause, scope, input, output, parameter;
  struct Value {
    std::string point;
    double x = 0, value = 0, sigma = -1;
    double simulated = 0;
    bool has_simulated = false;
  };
  std::vector<Value> values;     // in x order
  std::string law = "constant";  // "constant", "linear", "power"
  double a = 0, b = 0, b_sigma = -1, criterion = 0;
  std::vector<std::string> missing_at;  // points where the finding is not
  std::string text;                     // the sentence for the report
};

// Leave-one-out at an inner point: the scheduled extended model built without it (the point's
// simulation extended by scheduled_findings of the other points) against its own measurement,
// beside the simulation at that point and the point's own extended model; each the diagnosis'
// error metric (model_error) over the pairs the point's simulation has.
struct LeaveOneOut {
  std::string point;
  double x = 0;
  std::string from_lo, from_hi;  // the neighbours' points
  double error_simulation = -1, error_scheduled = -1, error_extended = -1;
  std::vector<std::string> left_out;  // findings not at both neighbours, not applied
  std::string refused;                // why no scheduled model was built ("" when one was)
};

struct EnvelopeReport {
  std::string schedule_by;
  std::vector<EnvelopePoint> points;  // in x order
  std::vector<StateTrack> tracks;
  std::vector<SlowState> slow_states;  // the plant's first, then by output
  std::vector<FindingLaw> findings;
  /// The scheduled extended model's file, relative to DIR (scheduled_model_at); "" when not
  /// written.
  std::string scheduled_model;
  std::vector<LeaveOneOut> leave_one_out;  // inner points, in x order
  bool plots = false;  // DIR/plots/roots and findings rendered (the markdown shows them)
};

/// Joins the points' results (see above). Points in any order; sorted by x.
EnvelopeReport join_points(std::vector<EnvelopePoint> points, const EnvelopeOptions& o = {});

/// The pictures in DIR/plots, PNG and SVG: `roots` (the root migration: each state's |root| in
/// rad/s, 1/tau for a real pole, wn for a pair, against the scheduling variable, sigma as error
/// bars; the twelve states at the most points) and `findings` (each finding's parameter per point
/// with its sigma and its law's curve). The data and the gnuplot script stay beside them. false
/// when gnuplot is missing or fails.
bool render_envelope_plots(const EnvelopeReport& r, const std::string& dir);

/// `fralab-envelope/1` (docs/formats.md §26) and its markdown.
Json envelope_json(const EnvelopeReport& r);
std::string envelope_markdown(const EnvelopeReport& r);

/// The folder name of a point: "<schedule_by>_<x>" (x without trailing zeros).
std::string envelope_point_name(const std::string& schedule_by, double x);

/// The findings of the scheduled extended model at x (points as join_points takes them, x within
/// their range): at a measured point its own findings; else each finding present at both points
/// around x, as the lower one's diagnosis gives it, its primary parameter from its law over the
/// points (FindingLaw), its other parameters linearly between the two. A finding at one of the two
/// only is left out and said in `left_out`. InputError for x outside the points' range (never
/// extrapolated).
std::vector<Finding> scheduled_findings(const std::vector<EnvelopePoint>& points, double x,
                                        const EnvelopeOptions& o = {},
                                        std::vector<std::string>* left_out = nullptr);

inline constexpr const char* kScheduledModelFormat = "fralab-scheduled-model/1";

/// The scheduled extended model `DIR/scheduled_model.json` (docs/formats.md §28) at x: its
/// simulation set at x (a member, or interpolated along its roots' tracks: plant/schedule.h)
/// extended by scheduled_findings(x) of its points' diagnoses (paths relative to the file).
/// InputError naming the file and key, or x outside the points' range.
Model scheduled_model_at(const std::string& file, double x);

/// A model spec as load_model_or_embedded reads it (a fralab-model/1 or fralab-ss/1 file, an
/// embedded name), and also "FILE@X" for a scheduled extended model FILE and a state model in a
/// .mat file (exchange/state_space_mat.h): what `--engine` and `--simulation` accept.
Model load_model_or_scheduled(const std::string& spec);

}  // namespace fralab
