#include "fralab/identify/fit_io.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>

#include "fralab/core/measure_dir.h"
#include "fralab/core/pair_id.h"
#include "fralab/identify/readers.h"
#include "fralab/identify/state_model.h"

namespace fralab {

void parse_delay_option(const std::string& text, FitOptions* o) {
  if (text == "auto") {
    o->delay = FitOptions::Delay::kAuto;
  } else if (text == "none") {
    o->delay = FitOptions::Delay::kNone;
  } else {
    try {
      size_t p = 0;
      double v = std::stod(text, &p);
      if (p != text.size() || !(v >= 0) || !std::isfinite(v)) throw std::invalid_argument("x");
      o->delay = FitOptions::Delay::kFixed;
      o->delay_s = v;
    } catch (const std::exception&) {
      throw InputError("--delay \"" + text + "\" must be auto, none or a delay in seconds >= 0");
    }
  }
}

std::vector<FitResult> fit_and_write(const std::vector<Frd>& curves, const FitOptions& o,
                                     const std::string& dir, const std::string& title) {
  const MeasureDir md_dir(dir);
  std::filesystem::create_directories(md_dir.tf_dir());
  std::vector<FitResult> fits;
  std::vector<MatrixEntry> entries;
  Json actuators = Json::array();
  for (const Frd& f : curves) {
    FitResult r = fit_tf(f.points, o);
    json_save_file(md_dir.tf(f.pair), fit_to_json(r, f.pair));
    const PairId id = PairId::parse(f.pair);
    if (id.actuator()) {
      Json a = fit_to_json(r, f.pair);
      a["text"] = tf_to_text(r.tf);
      actuators.push_back(a);
    } else if (id.path()) {
      entries.push_back({id.input, id.output, r});
    }
    fits.push_back(r);
  }
  TransferMatrix m = build_transfer_matrix(entries);
  Json j = transfer_matrix_json(m);
  std::map<std::string, std::vector<FrdPoint>> data;
  for (const Frd& f : curves) data[f.pair] = f.points;
  StateModel sm = build_state_model(m, data);
  j["state_model"] = state_model_json(sm);
  // The same from one pole set over the paths (docs/formats.md §10, "common_pole_set").
  const CommonPoleMatrix cpm = common_pole_matrix(m, data);
  std::optional<StateModel> sm_set;
  if (cpm.fit.status != PoleSetFit::Status::kFailed && !cpm.matrix.clusters.empty()) {
    sm_set = build_state_model(cpm.matrix, data);
    Json c = transfer_matrix_json(cpm.matrix);
    j["common_pole_set"] = {{"message", cpm.fit.message},
                            {"order", cpm.fit.order},
                            {"chi2_per_dof", cpm.fit.chi2_per_dof},
                            {"paths", cpm.paths},
                            {"common_poles", c["common_poles"]},
                            {"state_count", c["state_count"]},
                            {"state_model", state_model_json(*sm_set)}};
  }
  j["actuators"] = actuators;
  j["title"] = title;
  json_save_file(md_dir.transfer_matrix_json(), j);
  std::ofstream md(md_dir.transfer_matrix_md());
  md << transfer_matrix_markdown(m, title);
  md << state_model_markdown(sm);
  if (sm_set) {
    md << "\n## One pole set over the paths\n\n"
       << cpm.fit.message << ". " << cpm.matrix.clusters.size()
       << " poles that some path needs; the state model from them:"
       << "\n";
    std::string sec = state_model_markdown(*sm_set);
    const std::string head = "\n## State model\n\n";
    if (sec.compare(0, head.size(), head) == 0) sec = "\n" + sec.substr(head.size());
    md << sec;
  }
  md << "\n## Actuators\n\n| pair | tf | fit |\n|---|---|---|\n";
  for (const auto& a : actuators) {
    md << "| " << a["pair"].get<std::string>() << " | " << a["text"].get<std::string>() << " | "
       << a["fit"]["status"].get<std::string>() << " |\n";
  }
  return fits;
}

BodePlot fit_cross_plot(const Frd& data, const std::string& source, const Tf& fit,
                        const Tf* after_deletion, const std::string& stem) {
  std::vector<FrdPoint> pts;
  for (const auto& pt : data.points)
    if (pt.valid && pt.w > 0) pts.push_back(pt);
  std::sort(pts.begin(), pts.end(), [](const FrdPoint& a, const FrdPoint& b) { return a.w < b.w; });
  bool sig = true;
  for (const auto& pt : pts) sig = sig && pt.sigma > 0;
  BodePlot bp{
      (data.pair.empty() ? source : data.pair) + ": data and fit", stem, {}, {}, {}, {{"fit", {}}}};
  if (after_deletion) bp.models.push_back({"fit after deletion", {}});
  for (const auto& pt : pts) {
    bp.w.push_back(pt.w);
    bp.meas.push_back(pt.value());
    if (sig) bp.sigma.push_back(pt.sigma);
    bp.models[0].g.push_back(fit.at(pt.w));
    if (after_deletion) bp.models[1].g.push_back(after_deletion->at(pt.w));
  }
  return bp;
}

Json fit_output_json(const FitResult& r, const std::string& pair,
                     const std::vector<std::string>& deletions, Tf* kept) {
  Json j = fit_to_json(r, pair);
  *kept = deletions.empty() ? r.tf : delete_roots(r.tf, deletions);
  if (!deletions.empty()) {
    const Json k = tf_to_json(*kept);
    j["deleted"] = deletions;
    j["zeros"] = k["zeros"];
    j["poles"] = k["poles"];
  }
  return j;
}

}  // namespace fralab
