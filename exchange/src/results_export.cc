#include "fralab/exchange/results_export.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>

#include "fralab/core/error.h"
#include "fralab/core/frd.h"
#include "fralab/core/pair_id.h"
#include "fralab/core/text.h"
#include "fralab/core/tf.h"
#include "fralab/exchange/mat_file.h"
#include "fralab/identify/transfer_matrix.h"
#include "fralab/plant/model.h"

namespace fs = std::filesystem;

namespace fralab {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Results {
  std::vector<Frd> frd;
  struct Path {
    std::string pair, input, output;
    Tf tf;
    double fit_error = kNaN;
    std::string status;
  };
  std::vector<Path> tf;
  std::map<std::string, std::string> units;  // channel -> unit
  std::vector<std::string> inputs, outputs;  // the transfer matrix's
  Json state_model;                          // null when absent
};

}  // namespace

std::map<std::string, std::string> channel_units(const std::string& model_file) {
  std::map<std::string, std::string> units;
  if (!fs::exists(model_file)) return units;
  const Model m = load_model(model_file);
  for (const auto& in : m.inputs) units[in.name] = units[command_channel(in.name)] = in.units;
  for (const auto& out : m.outputs) units[out.name] = out.units;
  return units;
}

namespace {

std::vector<fs::path> json_files(const fs::path& dir) {
  std::vector<fs::path> out;
  if (!fs::is_directory(dir)) return out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".json") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

Results load_results(const std::string& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir + ": not a measure directory");
  Results r;
  for (const auto& f : json_files(fs::path(dir) / "frd")) r.frd.push_back(load_frd(f.string()));
  for (const auto& f : json_files(fs::path(dir) / "tf")) {
    const Json j = json_load_file(f.string());
    std::vector<std::string> ignored;
    Results::Path p;
    p.tf = tf_from_json(j, JsonWhere{f.string(), ""}, &ignored, true);
    p.pair = j.contains("pair") && j["pair"].is_string() ? j["pair"].get<std::string>()
                                                         : f.stem().string();
    if (p.pair.find(':') != std::string::npos) std::tie(p.input, p.output) = split_pair(p.pair);
    if (j.contains("fit") && j["fit"].is_object()) {
      const Json& fit = j["fit"];
      if (fit.contains("rms_rel_error") && fit["rms_rel_error"].is_number())
        p.fit_error = fit["rms_rel_error"].get<double>();
      if (fit.contains("status") && fit["status"].is_string())
        p.status = fit["status"].get<std::string>();
    }
    r.tf.push_back(std::move(p));
  }
  if (r.frd.empty() && r.tf.empty())
    throw InputError(dir + ": no frd/*.json and no tf/*.json (a `fralab measure` directory?)");
  const fs::path tm = fs::path(dir) / "transfer_matrix.json";
  if (fs::exists(tm)) {
    const Json j = json_load_file(tm.string());
    const JsonWhere w{tm.string(), ""};
    for (const char* key : {"inputs", "outputs"}) {
      const Json& a = json_array_member(j, w, key, true);
      for (const auto& n : a)
        if (n.is_string()) (std::string(key) == "inputs" ? r.inputs : r.outputs).push_back(n);
    }
    if (j.contains("state_model") && j["state_model"].is_object()) r.state_model = j["state_model"];
  }
  r.units = channel_units((fs::path(dir) / "engine.json").string());
  return r;
}

std::string unit_of(const Results& r, const std::string& channel) {
  auto it = r.units.find(channel);
  return it == r.units.end() ? "" : it->second;
}

std::string ratio_units(const Results& r, const std::string& pair) {
  if (pair.find(':') == std::string::npos) return "";
  const auto [e1, e2] = split_pair(pair);
  const std::string u1 = unit_of(r, e1), u2 = unit_of(r, e2);
  if (u1.empty() || u2.empty()) return "";
  return u2 + " per " + u1;
}

std::vector<std::complex<double>> locations(const std::vector<Root>& roots) {
  std::vector<std::complex<double>> out;
  for (const Root& x : roots)
    for (const auto& z : x.locations()) out.push_back(z);
  return out;
}

// A state-model JSON matrix (array of rows) as rows x cols column-major.
MatValue json_matrix(const Json& m, const std::string& where) {
  if (!m.is_array()) throw InputError(where + ": not a matrix");
  const size_t rows = m.size(), cols = rows ? m[0].size() : 0;
  std::vector<double> v(rows * cols);
  for (size_t i = 0; i < rows; ++i) {
    if (!m[i].is_array() || m[i].size() != cols) throw InputError(where + ": ragged matrix");
    for (size_t k = 0; k < cols; ++k) {
      if (!m[i][k].is_number()) throw InputError(where + ": not a number at " + std::to_string(i));
      v[k * rows + i] = m[i][k].get<double>();
    }
  }
  return MatValue::matrix(rows, cols, std::move(v));
}

std::string mat_field(const std::string& pair) {
  std::string s = pair_file_stem(pair);
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
  if (s.empty() || !std::isalpha(static_cast<unsigned char>(s[0]))) s = "p_" + s;
  return s.substr(0, 63);
}

std::string coeffs_text(const std::vector<double>& c) {
  std::string s;
  for (double v : c) s += (s.empty() ? "" : " ") + lossless(v);
  return s;
}

std::string roots_text(const std::vector<std::complex<double>>& z) {
  std::string s;
  for (const auto& v : z)
    s += (s.empty() ? "" : " ") + lossless(v.real()) + (v.imag() < 0 ? "" : "+") +
         lossless(v.imag()) + "j";
  return s;
}

std::string csv_quote(const std::string& s) {
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

namespace {

// The .mat's units: the frequency, phase and delay columns', then each channel's.
MatValue mat_units(const Results& r) {
  MatValue units = MatValue::structure();
  units.add("w", MatValue::str("rad/s"));
  units.add("f_hz", MatValue::str("Hz"));
  units.add("phase_deg", MatValue::str("deg"));
  units.add("delay_s", MatValue::str("s"));
  for (const auto& [ch, u] : r.units)
    if (is_mat_name(ch) && ch != "w" && ch != "f_hz" && ch != "phase_deg" && ch != "delay_s")
      units.add(ch, MatValue::str(u));
  return units;
}

// A curve as a .mat struct: its pair and channels, its points as columns (an unknown sigma or
// coherence NaN), its units.
MatValue mat_frd(const Results& r, const Frd& f) {
  MatValue s = MatValue::structure();
  std::vector<double> w, fhz, mag, ph, sig, coh, valid;
  std::vector<std::complex<double>> h;
  for (const auto& p : f.points) {
    w.push_back(p.w);
    fhz.push_back(p.w / (2 * std::numbers::pi));
    mag.push_back(p.mag);
    ph.push_back(p.phase_deg);
    h.push_back(p.value());
    sig.push_back(p.sigma >= 0 ? p.sigma : kNaN);
    coh.push_back(p.coherence >= 0 ? p.coherence : kNaN);
    valid.push_back(p.valid ? 1.0 : 0.0);
  }
  s.add("pair", MatValue::str(f.pair));
  const auto [e1, e2] = split_pair(f.pair);
  s.add("input", MatValue::str(e1));
  s.add("output", MatValue::str(e2));
  s.add("w", MatValue::column(w));
  s.add("f_hz", MatValue::column(fhz));
  s.add("mag", MatValue::column(mag));
  s.add("phase_deg", MatValue::column(ph));
  s.add("H", MatValue::complex_column(h));
  s.add("sigma", MatValue::column(sig));
  s.add("coherence", MatValue::column(coh));
  s.add("valid", MatValue::column(valid));
  s.add("units", MatValue::str(ratio_units(r, f.pair)));
  return s;
}

// A fitted transfer function as a .mat struct: its text, gain, delay, polynomials, roots, fit
// error, status and units.
MatValue mat_tf(const Results& r, const Results::Path& p) {
  MatValue s = MatValue::structure();
  s.add("pair", MatValue::str(p.pair));
  s.add("input", MatValue::str(p.input));
  s.add("output", MatValue::str(p.output));
  s.add("text", MatValue::str(tf_to_text(p.tf)));
  s.add("gain", MatValue::scalar(p.tf.gain));
  s.add("delay_s", MatValue::scalar(p.tf.delay_s));
  const auto num = p.tf.numerator_coefficients(), den = p.tf.denominator_coefficients();
  s.add("num", MatValue::matrix(1, num.size(), num));
  s.add("den", MatValue::matrix(1, den.size(), den));
  s.add("zeros", MatValue::complex_column(locations(p.tf.zeros)));
  s.add("poles", MatValue::complex_column(locations(p.tf.poles)));
  s.add("fit_error", MatValue::scalar(p.fit_error));
  s.add("status", MatValue::str(p.status));
  s.add("units", MatValue::str(ratio_units(r, p.pair)));
  return s;
}

}  // namespace

ExportSummary export_results_mat(const std::string& measure_dir, const std::string& out_file) {
  const Results r = load_results(measure_dir);
  std::vector<std::pair<std::string, MatValue>> vars;
  vars.emplace_back("inputs", MatValue::str_list(r.inputs));
  vars.emplace_back("outputs", MatValue::str_list(r.outputs));
  vars.emplace_back("units", mat_units(r));
  ExportSummary sum;
  MatValue frd = MatValue::structure();
  for (const Frd& f : r.frd) {
    frd.add(mat_field(f.pair), mat_frd(r, f));
    ++sum.frd;
  }
  vars.emplace_back("frd", frd);
  MatValue tf = MatValue::structure();
  for (const auto& p : r.tf) {
    tf.add(mat_field(p.pair), mat_tf(r, p));
    ++sum.tf;
  }
  vars.emplace_back("tf", tf);
  if (!r.state_model.is_null()) {
    const Json& j = r.state_model;
    const std::string where = measure_dir + "/transfer_matrix.json: /state_model";
    MatValue ss = MatValue::structure();
    for (const char* k : {"A", "B", "C", "D", "delay_s"})
      if (j.contains(k)) ss.add(k, json_matrix(j[k], where + "/" + k));
    ss.add("inputs", MatValue::str_list(r.inputs));
    ss.add("outputs", MatValue::str_list(r.outputs));
    if (j.contains("error") && j["error"].is_number())
      ss.add("error", MatValue::scalar(j["error"].get<double>()));
    vars.emplace_back("ss", ss);
    sum.state_model = true;
  }
  write_mat_file(out_file, vars);
  sum.written = out_file;
  return sum;
}

ExportSummary export_results_csv(const std::string& measure_dir, const std::string& out_dir) {
  const Results r = load_results(measure_dir);
  fs::create_directories(fs::path(out_dir) / "frd");
  auto open = [&](const fs::path& p) {
    std::ofstream f(p);
    if (!f) throw InputError(p.string() + ": cannot be written");
    return f;
  };
  ExportSummary sum;
  for (const Frd& d : r.frd) {
    const fs::path p = fs::path(out_dir) / "frd" / (pair_file_stem(d.pair) + ".csv");
    std::ofstream f = open(p);
    f << "# pair " << d.pair << ": the response " << split_pair(d.pair).second << " / "
      << split_pair(d.pair).first;
    const std::string u = ratio_units(r, d.pair);
    if (!u.empty()) f << " in " << u;
    f << "; w rad/s, f_hz Hz, phase_deg degrees, sigma of the complex ratio (empty: unknown)\n"
      << "w,f_hz,mag,mag_db,phase_deg,re,im,sigma,coherence,valid\n";
    for (const auto& x : d.points) {
      const auto h = x.value();
      f << lossless(x.w) << "," << lossless(x.w / (2 * std::numbers::pi)) << "," << lossless(x.mag)
        << "," << lossless(20 * std::log10(x.mag)) << "," << lossless(x.phase_deg) << ","
        << lossless(h.real()) << "," << lossless(h.imag()) << ","
        << (x.sigma >= 0 ? lossless(x.sigma) : "") << ","
        << (x.coherence >= 0 ? lossless(x.coherence) : "") << "," << (x.valid ? 1 : 0) << "\n";
    }
    ++sum.frd;
  }
  {
    std::ofstream f = open(fs::path(out_dir) / "tf.csv");
    f << "# G(s) = num(s)/den(s) e^(-s delay_s); num, den: coefficients of s, highest power "
         "first; zeros, poles in rad/s\n"
      << "pair,input,output,gain,delay_s,num,den,zeros,poles,fit_error,units,text\n";
    for (const auto& p : r.tf) {
      f << csv_quote(p.pair) << "," << csv_quote(p.input) << "," << csv_quote(p.output) << ","
        << lossless(p.tf.gain) << "," << lossless(p.tf.delay_s) << ","
        << csv_quote(coeffs_text(p.tf.numerator_coefficients())) << ","
        << csv_quote(coeffs_text(p.tf.denominator_coefficients())) << ","
        << csv_quote(roots_text(locations(p.tf.zeros))) << ","
        << csv_quote(roots_text(locations(p.tf.poles))) << ","
        << (std::isnan(p.fit_error) ? "" : lossless(p.fit_error)) << ","
        << csv_quote(ratio_units(r, p.pair)) << "," << csv_quote(tf_to_text(p.tf)) << "\n";
      ++sum.tf;
    }
  }
  if (!r.state_model.is_null()) {
    const Json& j = r.state_model;
    const int n = j.contains("A") && j["A"].is_array() ? int(j["A"].size()) : 0;
    std::vector<std::string> states;
    for (int i = 0; i < n; ++i) states.push_back("x" + std::to_string(i + 1));
    auto write = [&](const char* key, const std::vector<std::string>& rows,
                     const std::vector<std::string>& cols) {
      if (!j.contains(key)) return;
      const Json& m = j[key];
      std::ofstream f = open(fs::path(out_dir) / (std::string("ss_") + key + ".csv"));
      f << key;
      for (const auto& c : cols) f << "," << c;
      f << "\n";
      for (size_t i = 0; i < m.size(); ++i) {
        f << (i < rows.size() ? rows[i] : std::to_string(i));
        for (const auto& v : m[i]) f << "," << (v.is_number() ? lossless(v.get<double>()) : "");
        f << "\n";
      }
    };
    write("A", states, states);
    write("B", states, r.inputs);
    write("C", r.outputs, states);
    write("D", r.outputs, r.inputs);
    write("delay_s", r.outputs, r.inputs);
    sum.state_model = true;
  }
  {
    std::ofstream f = open(fs::path(out_dir) / "units.csv");
    f << "channel,units\n";
    for (const auto& [ch, u] : r.units) f << csv_quote(ch) << "," << csv_quote(u) << "\n";
  }
  sum.written = out_dir;
  return sum;
}

}  // namespace fralab
