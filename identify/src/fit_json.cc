// The JSON of a fit (docs/formats.md §1): the tf with its delay, and the fit's figures, root table
// and Pade sets beside it.
#include <cmath>
#include <numbers>

#include "fralab/identify/tfns.h"

namespace fralab {

Json fit_to_json(const FitResult& r, const std::string& pair) {
  Json j = tf_to_json(r.tf);
  j["delay_s"] = r.tf.delay_s;
  if (!pair.empty()) j["pair"] = pair;
  j["fit"] = {{"status", r.status_str()},
              {"message", r.message},
              {"num_order", r.num_order},
              {"den_order", r.den_order},
              {"iterations", r.iterations},
              {"e_phi", r.e_phi},
              {"e_n", r.e_n},
              {"rms_rel_error", r.rms_rel_error},
              {"max_rel_error", r.max_rel_error},
              {"n_points", r.n_points},
              {"unstable_reflected", r.unstable_reflected}};
  if (r.chi2_per_dof >= 0) j["fit"]["chi2_per_dof"] = r.chi2_per_dof;
  if (r.gain_rel_sigma >= 0) j["fit"]["gain_rel_sigma"] = r.gain_rel_sigma;
  if (r.delay_sigma_s >= 0) j["fit"]["delay_sigma_s"] = r.delay_sigma_s;
  if (r.noise_rel >= 0) j["fit"]["noise_rel"] = r.noise_rel;
  if (r.noise_abs >= 0) j["fit"]["noise_abs"] = r.noise_abs;
  if (r.sigma_scale != 1) j["fit"]["sigma_scale"] = r.sigma_scale;
  auto roots = [](const std::vector<RootInfo>& v) {
    Json a = Json::array();
    for (const auto& i : v) {
      Json r{{"real", i.real},
             {"imag", i.imag},
             {"wn", i.wn},
             {"zeta", i.zeta},
             {"f_hz", i.wn / (2 * std::numbers::pi)}};
      if (i.rel_sigma >= 0) r["rel_sigma"] = i.rel_sigma;
      a.push_back(r);
    }
    return a;
  };
  j["roots"] = {{"zeros", roots(r.zero_info)}, {"poles", roots(r.pole_info)}};
  j["pade"] = Json::array();
  for (const auto& s : r.pade)
    j["pade"].push_back(
        {{"zero", root_to_json(s.zero)}, {"pole", root_to_json(s.pole)}, {"delay_s", s.delay_s}});
  j["pade_delay_s"] = r.pade_delay_s;
  return j;
}

}  // namespace fralab
