#include "fralab/core/frd.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace fralab {

std::complex<double> FrdPoint::value() const {
  return std::polar(mag, phase_deg * std::numbers::pi / 180.0);
}

std::pair<std::string, std::string> split_pair(const std::string& pair) {
  auto c = pair.find(':');
  if (c == std::string::npos || c == 0 || c + 1 == pair.size() ||
      pair.find(':', c + 1) != std::string::npos) {
    throw InputError("pair \"" + pair +
                     "\" must be written E1:E2 (the response E2/E1), e.g. Wf:P3");
  }
  return {pair.substr(0, c), pair.substr(c + 1)};
}

std::string pair_file_stem(const std::string& pair) {
  auto [a, b] = split_pair(pair);
  return a + "_" + b;
}

Json frd_to_json(const Frd& frd) {
  Json j{{"format", kFrdFormat}, {"pair", frd.pair}, {"points", Json::array()}};
  for (const FrdPoint& p : frd.points) {
    Json jp{{"w", p.w},
            {"f_hz", p.w / (2 * std::numbers::pi)},
            {"mag", p.mag},
            {"phase_deg", p.phase_deg}};
    if (p.sigma > 0) jp["sigma"] = p.sigma;
    if (p.coherence >= 0) jp["coherence"] = p.coherence;
    jp["h2_rel"] = p.h2_rel;
    jp["h3_rel"] = p.h3_rel;
    if (p.nl_rel >= 0) jp["nl_rel"] = p.nl_rel;
    if (p.sigma_noise >= 0) jp["sigma_noise"] = p.sigma_noise;
    if (p.sigma_nl >= 0) jp["sigma_nl"] = p.sigma_nl;
    if (p.realisations > 0) jp["realisations"] = p.realisations;
    if (p.line_amplitude > 0) jp["line_amplitude"] = p.line_amplitude;
    jp["n_cycles"] = p.n_cycles;
    jp["step"] = p.step;
    if (!p.input.empty()) jp["input"] = p.input;
    if (p.amplitude > 0) jp["amplitude"] = p.amplitude;
    jp["valid"] = p.valid;
    if (!p.note.empty()) jp["note"] = p.note;
    j["points"].push_back(jp);
  }
  return j;
}

Frd frd_from_json(const Json& j, const std::string& source) {
  JsonWhere root{source, ""};
  json_require_object(j, root);
  const std::string fmt = json_string_member(j, root, "format");
  if (fmt != kFrdFormat)
    json_fail(root / "format",
              "expected \"" + std::string(kFrdFormat) + "\", found \"" + fmt + "\"");
  Frd f;
  f.source = source;
  f.pair = json_string_member(j, root, "pair");
  split_pair(f.pair);
  const Json& pts = json_array_member(j, root, "points");
  for (size_t i = 0; i < pts.size(); ++i) {
    JsonWhere w = root / "points" / i;
    const Json& jp = pts[i];
    FrdPoint p;
    p.w = json_number_member(jp, w, "w");
    if (!(p.w > 0)) json_fail(w / "w", "w must be > 0 rad/s");
    p.mag = json_number_member(jp, w, "mag");
    if (p.mag < 0) json_fail(w / "mag", "mag is an amplitude ratio (not dB) and must be >= 0");
    p.phase_deg = json_number_member(jp, w, "phase_deg");
    p.sigma = json_number_member(jp, w, "sigma", -1.0);
    p.coherence = json_number_member(jp, w, "coherence", -1.0);
    p.h2_rel = json_number_member(jp, w, "h2_rel", 0.0);
    p.h3_rel = json_number_member(jp, w, "h3_rel", 0.0);
    p.nl_rel = json_number_member(jp, w, "nl_rel", -1.0);
    p.sigma_noise = json_number_member(jp, w, "sigma_noise", -1.0);
    p.sigma_nl = json_number_member(jp, w, "sigma_nl", -1.0);
    p.line_amplitude = json_number_member(jp, w, "line_amplitude", 0.0);
    // Counts and step numbers: whole numbers an int holds (a converted 5e11 is undefined).
    auto whole = [&](const char* key, double dflt) {
      const double v = json_number_member(jp, w, key, dflt);
      if (v != std::floor(v) || std::abs(v) > 1e9) json_fail(w / key, "a whole number is needed");
      return static_cast<int>(v);
    };
    p.n_cycles = whole("n_cycles", 0.0);
    p.step = whole("step", -1.0);
    p.realisations = whole("realisations", 0.0);
    if (jp.contains("sigma_noise") && p.sigma_noise < 0)
      json_fail(w / "sigma_noise", "sigma_noise must be >= 0 (omit it when unknown)");
    if (jp.contains("sigma_nl") && p.sigma_nl < 0)
      json_fail(w / "sigma_nl", "sigma_nl must be >= 0 (omit it when unknown)");
    p.amplitude = json_number_member(jp, w, "amplitude", 0.0);
    if (jp.contains("input") && jp["input"].is_string()) p.input = jp["input"];
    if (jp.contains("valid")) p.valid = json_bool(jp["valid"], w / "valid");
    if (jp.contains("note") && jp["note"].is_string()) p.note = jp["note"];
    if (jp.contains("sigma") && !(p.sigma > 0))
      json_fail(w / "sigma", "sigma " + std::to_string(p.sigma) +
                                 " must be > 0 (the standard deviation; omit it when unknown)");
    if (jp.contains("coherence") && p.coherence < 0)
      json_fail(w / "coherence", "coherence must lie in [0, 1]");
    if (const std::string bad = frd_point_problem(p); !bad.empty()) json_fail(w, bad);
    f.points.push_back(p);
  }
  std::stable_sort(f.points.begin(), f.points.end(),
                   [](const FrdPoint& a, const FrdPoint& b) { return a.w < b.w; });
  return f;
}

std::string frd_point_problem(const FrdPoint& p) {
  auto num = [](double v) { return std::to_string(v); };
  if (!std::isfinite(p.w) || !(p.w > 0)) return "w " + num(p.w) + " must be a finite > 0 rad/s";
  if (!std::isfinite(p.mag) || p.mag < 0 || p.mag > kMaxFrdMagnitude)
    return "mag " + num(p.mag) + " is not an amplitude ratio in [0, 1e12]";
  if (!std::isfinite(p.phase_deg)) return "phase_deg is not finite";
  if (p.sigma >= 0 && (!std::isfinite(p.sigma) || p.sigma == 0))
    return "sigma " + num(p.sigma) + " must be a finite > 0 (omit it when unknown)";
  if (!std::isfinite(p.sigma)) return "sigma is not finite";
  if (!std::isfinite(p.coherence) || p.coherence > 1 + 1e-9)
    return "coherence " + num(p.coherence) + " must lie in [0, 1]";
  if (!std::isfinite(p.sigma_noise) || !std::isfinite(p.sigma_nl))
    return "sigma_noise or sigma_nl is not finite";
  if (!std::isfinite(p.line_amplitude) || p.line_amplitude < 0)
    return "line_amplitude " + num(p.line_amplitude) + " must be a finite >= 0";
  if (p.realisations < 0) return "realisations " + std::to_string(p.realisations) + " is < 0";
  return "";
}

Frd load_frd(const std::string& file) { return frd_from_json(json_load_file(file), file); }
void save_frd(const std::string& file, const Frd& frd) { json_save_file(file, frd_to_json(frd)); }

}  // namespace fralab
