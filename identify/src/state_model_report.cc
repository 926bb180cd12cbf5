// The state model's JSON (docs/formats.md) and its Markdown section of transfer_matrix.md.
#include <sstream>

#include "fralab/identify/state_model.h"

namespace fralab {

Json state_model_json(const StateModel& s) {
  auto mat = [](const Eigen::MatrixXd& M) {
    Json a = Json::array();
    for (int r = 0; r < M.rows(); ++r) {
      Json row = Json::array();
      for (int c = 0; c < M.cols(); ++c) row.push_back(M(r, c));
      a.push_back(row);
    }
    return a;
  };
  Json checks = Json::object();
  for (const auto& [k, c] : s.path_check)
    checks[k] = Json{{"fit_status", c.fit_status},
                     {"points", c.points},
                     {"clear_points", c.clear},
                     {"error", c.error},
                     {"chi2_per_point", c.chi2_per_point},
                     {"fit_chi2_per_point", c.fit_chi2_per_point},
                     {"model_silent", c.model_silent}};
  return Json{
      {"order", s.order},
      {"inputs", s.inputs},
      {"outputs", s.outputs},
      {"A", mat(s.A)},
      {"B", mat(s.B)},
      {"C", mat(s.C)},
      {"D", mat(s.D)},
      {"delay_s", mat(s.delay_s)},
      {"path_error", s.path_error},
      {"path_check", checks},
      {"error", s.error},
      {"rank1_loss", s.rank1_loss},
      {"rank", s.rank},
      {"factor_fit", {{"start_chi2", s.start_chi2}, {"chi2", s.fit_chi2}, {"sweeps", s.sweeps}}},
      {"metric",
       "rms over the points measured to better than 30 % (sigma <= 0.3 |G|) of "
       "|ln(G_model/G_measured)|; error: over the paths in the model"}};
}

namespace {

// "rank one everywhere", or "rank one but at [s/3.38 + 1] (rank 2), ..." naming the clusters above.
std::string ranks_text(const StateModel& s) {
  std::ostringstream t;
  int above = 0;
  for (int r : s.rank) above += r > 1;
  if (above == 0) return "rank one everywhere";
  t << "rank one but at";
  const char* sep = " ";
  for (size_t k = 0; k < s.rank.size(); ++k) {
    if (s.rank[k] < 2) continue;
    t << sep << factor_text(s.poles[k]) << " (rank " << s.rank[k] << ")";
    sep = ", ";
  }
  return t.str();
}

}  // namespace

std::string state_model_markdown(const StateModel& s) {
  auto num = [](double v) {
    if (v < 0) return std::string("-");
    std::ostringstream t;
    t.precision(3);
    t << v;
    return t.str();
  };
  int in_model = 0;
  for (const auto& [k, c] : s.path_check) in_model += c.fit_status == "converged";
  std::ostringstream md;
  md << "\n## State model\n\nOrder " << s.order
     << " (one state per distinct real pole, two per pair, times the rank of its residue matrix: "
     << ranks_text(s)
     << "); "
        "error against the data (rms |ln(G_model/G_measured)| over the points measured to better "
        "than 30 %): "
     << num(s.error) << " over the " << in_model
     << " paths in the model. chi2 per point: mean |G - G_measured|^2 / sigma^2 (about 1: as "
        "good as the noise), the state model's beside the path's own fit's (0 for no response)."
        "\n\n| path | fit | points (clear) | error | chi2 per point: model / fit |\n"
        "|---|---|---|---|---|\n";
  for (const auto& [k, c] : s.path_check)
    md << "| " << k << " | " << c.fit_status << " | " << c.points << " (" << c.clear << ") | "
       << (c.model_silent ? std::string("no response in the model") : num(c.error)) << " | "
       << num(c.chi2_per_point) << " / " << num(c.fit_chi2_per_point) << " |\n";
  return md.str();
}

}  // namespace fralab
