// Internal to the identify library: fit_tf's search for the orders, the delay hypothesis and the
// model (docs/method/identifier.md, steps 5-7). Not installed.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "delay_search.h"
#include "fit_data.h"
#include "fralab/identify/tfns.h"
#include "fralab/identify/vector_fitting.h"

namespace fralab::tfns_detail {

// A model the search has fitted, and how it scores on the data.
struct Candidate {
  Tf tf;
  Score s;
  bool ok = false, adequate = false, free_delay = false;
  bool unfinished = false;  // its refinement stopped at the screening budget
  bool from_vf = false;     // its SK started from vector fitting's poles
  double chi2dof = -1, misfit = 0;
  double rank = 0;  // sse, times 1e6 for a non-physical model (ranked below any physical one)
  bool nonphysical = false;
  int params = 0, iterations = 0, reflected = 0;
  double e_phi = 0;
  double crit = 0;  // among adequate candidates the lowest wins: chi^2 + kappa p
};

// The parameters of model t: the gain, its roots, and the delay when it is fitted.
int n_params(const Tf& t, bool free_delay);

// The misfit relative to the adequacy threshold (<= 1: adequate): chi2/dof over 1 + 3/sqrt(N) with
// sigma (*chi2dof set), else E_N over c_n.
double misfit(const Data& d, const Score& s, int params, const FitOptions& o, double* chi2dof);

// The order search: for each delay hypothesis (none, or fixed; with delay auto also a searched
// one) an order loop raises the denominator order n and tries the numerator orders m at each, from
// SK's and vector fitting's starts refined by output error; the adequate candidate of lowest
// criterion wins. With sigma and no order adequate, the search runs once more with sigma scaled to
// the data's scatter. Then the chosen model is simplified (simplify.h).
//
// Works on d in place (the pass against the scatter scales its sigma and weights) and on delays'
// caches, both shared with the noise estimate before it.
class OrderSearch {
 public:
  // noise_estimated: the data's sigma is a level estimated or imposed without sigma (no nested
  // starts, see start_nested).
  OrderSearch(Data& d, const FitOptions& o, DelaySearch& delays, bool noise_estimated);

  // Chooses the model: the order loops of each delay hypothesis, the winner finished and weighed
  // against the candidate of lowest criterion, and with sigma and no order adequate a second pass
  // with sigma scaled. False when no order could be fitted.
  bool choose_model();
  // Simplifies the chosen model: prune, then prefer_lags (simplify.h).
  void simplify();

  // The highest denominator order tried (max_den_order, below the number of points).
  int max_order() const { return max_n_; }
  // The chosen model.
  const Candidate& chosen() const { return fin_; }
  // The chosen model passes: adequate, or chosen by the criterion over an adequate one.
  bool passes() const { return fin_.adequate || by_crit_; }
  // Completes res for the chosen model (after fill_result): the figures against the sigma given
  // when sigma was scaled, and what the message must add (chosen by the criterion, a zero
  // replaced by a lag).
  void annotate(FitResult& res) const;

 private:
  struct Loop;

  void evaluate(Candidate& c);
  void refine_candidate(Candidate& c, int budget);
  void consider(const Candidate& c);
  Candidate from_sk(const Sk& sk, double tau, bool free_delay);
  const std::vector<C>* vf_poles(double tau, int n);

  std::vector<Candidate> delay_hypotheses();
  /// One order loop's delay hypothesis and limits (order_loop).
  struct LoopSpec {
    double tau0 = 0;           // the delay hypothesis (free delay: where its starts are searched)
    bool free_delay = false;   // the delay refined jointly with the roots
    int max_params = 1 << 20;  // candidates with this many parameters or more are not tried
    int top_n = 0;             // the highest denominator order tried
    size_t n_starts = 1;       // with a free delay: the delay starts per order
    bool one_more = false;     // past the first adequate order, two more orders tried
  };
  Candidate order_loop(const LoopSpec& spec);
  Candidate fit_order(Loop& l, int n);
  Candidate fit_from_starts(const std::vector<double>& starts, int n, int m, bool free_delay,
                            bool vf_here, bool past_adequate);
  void start_nested(Candidate& c, const Candidate& base, int n, int m);
  void cut_dipole(Candidate& c);
  std::optional<Candidate> conclude_order(Loop& l, int n, Candidate& best_n);

  void finish_choice();
  void prefer_criterion();
  void scale_sigma();
  void unscale_sigma();

  Data& d_;
  const FitOptions& o_;
  DelaySearch& delays_;
  const bool noise_estimated_;
  const int max_n_;                // the highest denominator order
  const double kappa_;             // the criterion's penalty per parameter
  double min_chi2dof_ = INFINITY;  // the lowest chi^2/dof of any physical candidate of this pass
  Candidate low_;  // the lowest criterion among the candidates passing at kCritSigmas (consider)
  // Vector fitting's n poles of the data with delay tau removed, kept per (tau, n): every
  // numerator order of n starts from them.
  struct VfPoles {
    double tau;
    int n;
    VectorFitResult r;
  };
  std::vector<VfPoles> vf_cache_;

  int top_tried_ = 0;       // the highest denominator order any order loop tried
  int stalled_at_ = 0;      // the order at which a loop stopped for want of improvement (0: none)
  Candidate fin_;           // the chosen model
  double sigma_scale_ = 1;  // sigma's scale in the pass that chose it
  bool by_crit_ = false;    // chosen by the criterion over an adequate candidate
  std::string by_crit_note_, lag_note_;
};

}  // namespace fralab::tfns_detail
