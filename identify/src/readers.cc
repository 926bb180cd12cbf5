#include "fralab/identify/readers.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

namespace fralab {
namespace {

std::string trim(const std::string& s) {
  size_t a = s.find_first_not_of(" \t\r"), b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

double to_number(const std::string& text, const std::string& where) {
  std::string t = trim(text);
  try {
    size_t p = 0;
    double v = std::stod(t, &p);
    if (p != t.size() || !std::isfinite(v)) throw std::invalid_argument("x");
    return v;
  } catch (const std::exception&) {
    throw InputError(where + ": \"" + t + "\" is not a number");
  }
}

std::string field(const std::string& line, size_t col1, size_t width) {  // 1-based column
  if (line.size() < col1) return std::string(width, ' ');
  std::string f = line.substr(col1 - 1, width);
  f.resize(width, ' ');
  return f;
}

FrdPoint from_polar(double w, double mag, double ph_rad) {
  FrdPoint p;
  p.w = w;
  p.mag = mag;
  p.phase_deg = ph_rad * 180 / std::numbers::pi;
  return p;
}

}  // namespace

namespace {

// The columns of a CSV curve's header (-1: absent): the frequency (w in rad/s or f_hz), the value
// (re and im, or mag or mag_db with phase_deg), and the optional sigma, coherence and valid.
struct FrdCsvColumns {
  size_t count = 0;
  int w = -1, f_hz = -1, mag = -1, mag_db = -1, phase = -1, re = -1, im = -1, sigma = -1,
      coherence = -1, valid = -1;
  bool rect() const { return re >= 0 && im >= 0; }
};

FrdCsvColumns frd_csv_columns(const std::string& header, const std::string& where) {
  std::vector<std::string> cols;
  std::stringstream ss(header);
  for (std::string c; std::getline(ss, c, ',');) cols.push_back(trim(c));
  auto idx = [&](const char* n) {
    auto it = std::find(cols.begin(), cols.end(), n);
    return it == cols.end() ? -1 : int(it - cols.begin());
  };
  FrdCsvColumns c;
  c.count = cols.size();
  c.w = idx("w"), c.f_hz = idx("f_hz"), c.mag = idx("mag"), c.mag_db = idx("mag_db");
  c.phase = idx("phase_deg"), c.re = idx("re"), c.im = idx("im"), c.sigma = idx("sigma");
  c.coherence = idx("coherence"), c.valid = idx("valid");
  if (c.w < 0 && c.f_hz < 0)
    throw InputError(where + ": the header names no frequency column (w or f_hz)");
  if (!c.rect() && ((c.mag < 0 && c.mag_db < 0) || c.phase < 0))
    throw InputError(where + ": the header needs mag or mag_db with phase_deg, or re and im");
  return c;
}

// One data row's point: its frequency and value, then the optional cells (an empty sigma or
// coherence cell is unknown, as fralab export --to csv writes it; valid is 1 or 0, a point the
// analyser refused staying refused).
FrdPoint frd_csv_point(const std::vector<std::string>& v, const FrdCsvColumns& c,
                       const std::string& where) {
  if (v.size() < c.count)
    throw InputError(where + ": " + std::to_string(v.size()) + " fields, the header has " +
                     std::to_string(c.count));
  const double w =
      c.w >= 0 ? to_number(v[c.w], where) : 2 * std::numbers::pi * to_number(v[c.f_hz], where);
  if (!(w > 0)) throw InputError(where + ": frequency must be > 0");
  FrdPoint p;
  if (c.rect()) {
    std::complex<double> g(to_number(v[c.re], where), to_number(v[c.im], where));
    p = from_polar(w, std::abs(g), std::arg(g));
  } else {
    double mag = c.mag >= 0 ? to_number(v[c.mag], where)
                            : std::pow(10.0, to_number(v[c.mag_db], where) / 20);
    p = from_polar(w, mag, to_number(v[c.phase], where) * std::numbers::pi / 180);
  }
  if (c.sigma >= 0 && !trim(v[c.sigma]).empty()) {
    p.sigma = to_number(v[c.sigma], where);
    if (!(p.sigma > 0))
      throw InputError(where + ": sigma must be > 0 (leave the cell empty when unknown)");
  }
  if (c.coherence >= 0 && !trim(v[c.coherence]).empty()) {
    p.coherence = to_number(v[c.coherence], where);
    if (!(p.coherence >= 0 && p.coherence <= 1))
      throw InputError(where + ": coherence must be in [0, 1] (leave the cell empty when unknown)");
  }
  if (c.valid >= 0 && !trim(v[c.valid]).empty()) {
    const double ok = to_number(v[c.valid], where);
    if (ok != 0 && ok != 1) throw InputError(where + ": valid must be 1 or 0");
    p.valid = ok == 1;
  }
  if (const std::string bad = frd_point_problem(p); !bad.empty())
    throw InputError(where + ": " + bad);
  return p;
}

// A TFNS control card (C: starting orders and the convergence constants; P or Z: roots to delete;
// O: the output options, ignored) into r.
void tfns_control_card(const std::string& line, const std::string& where, FitInput& r) {
  const char flag = line.empty() ? ' ' : line[0];
  if (flag == 'C') {
    r.has_control = true;
    std::string nd = trim(field(line, 2, 9)), nn = trim(field(line, 11, 10));
    auto order = [&](const std::string& text, const std::string& at) {
      const double v = to_number(text, at);
      if (!(v >= 0 && v <= 40 && v == std::floor(v)))
        throw InputError(at + ": an order is a whole number 0-40, found " + text);
      return int(v);
    };
    if (!nd.empty()) r.options.den_order_start = order(nd, where + " (C card, columns 2-10)");
    if (!nn.empty()) r.options.num_order_start = order(nn, where + " (C card, columns 11-20)");
    std::string cs = trim(field(line, 21, 10)), ct = trim(field(line, 31, 10));
    if (!cs.empty()) r.options.c_phi = to_number(cs, where + " (C card, columns 21-30)");
    if (!ct.empty()) r.options.c_n = to_number(ct, where + " (C card, columns 31-40)");
    r.options.max_den_order = std::max(r.options.max_den_order, r.options.den_order_start);
  } else if (flag == 'P' || flag == 'Z') {
    for (size_t c = 1; c + 2 <= line.size(); c += 4) {
      std::string f = trim(field(line, c, 4));
      if (f.empty()) break;
      if ((f[0] != 'P' && f[0] != 'Z') || f.size() != 3)
        throw InputError(where + ": root deletion field \"" + f + "\" must be like P03 or Z02");
      r.deletions.push_back(f);
    }
  } else if (flag != 'O' && !trim(line).empty()) {
    throw InputError(where + ": unknown control card '" + std::string(1, flag) +
                     "' (C, O, P, Z or *)");
  }
}

// A TFNS data card's point (blank or B: magnitude in dB unless M, phase in degrees unless R; P:
// dB and degrees only where marked D; R: real and imaginary), its frequency (rad/s, or Hz
// marked H) above last_w.
FrdPoint tfns_data_card(const std::string& line, const std::string& where, double last_w) {
  const char flag = line[0];
  if (flag != ' ' && flag != 'B' && flag != 'P' && flag != 'R') {
    throw InputError(where + ": data card type '" + std::string(1, flag) +
                     "' must be blank, B, P or R");
  }
  std::string ff = field(line, 15, 15), f1 = field(line, 30, 15), f2 = field(line, 45, 15);
  double w = 0;
  if (ff[0] == 'H' || ff[0] == 'R') {
    w = to_number(ff.substr(1), where + " (frequency, columns 15-29)");
    if (ff[0] == 'H') w *= 2 * std::numbers::pi;
  } else {
    w = to_number(ff, where + " (frequency, columns 15-29)");
  }
  if (!(w > 0)) throw InputError(where + ": frequency must be > 0");
  if (w <= last_w)
    throw InputError(where + ": cards must be in ascending frequency (" + std::to_string(w) +
                     " rad/s after " + std::to_string(last_w) + ")");
  auto val = [&](const std::string& f, const char* cols, char* unit) {
    *unit = (f[0] == 'D' || f[0] == 'M' || f[0] == 'R') ? f[0] : ' ';
    return to_number(*unit == ' ' ? f : f.substr(1), where + " (" + cols + ")");
  };
  char u1, u2;
  double a = val(f1, "columns 30-44", &u1), b = val(f2, "columns 45-59", &u2);
  if (flag == 'R') {
    std::complex<double> g(a, b);
    return from_polar(w, std::abs(g), std::arg(g));
  }
  const bool db = flag == 'P' ? u1 == 'D' : u1 != 'M';
  const bool deg = flag == 'P' ? u2 == 'D' : u2 != 'R';
  return from_polar(w, db ? std::pow(10.0, a / 20) : a, deg ? b * std::numbers::pi / 180 : b);
}

}  // namespace

Frd read_frd_csv(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file + ": cannot open for reading");
  std::string line;
  int ln = 0;
  while (std::getline(in, line)) {
    ++ln;
    if (!trim(line).empty() && trim(line)[0] != '#') break;
  }
  const FrdCsvColumns cols = frd_csv_columns(line, file + ":" + std::to_string(ln));
  Frd f;
  f.source = file;
  f.pair = "E1:E2";
  while (std::getline(in, line)) {
    ++ln;
    if (trim(line).empty() || trim(line)[0] == '#') continue;
    std::vector<std::string> v;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) v.push_back(c);
    f.points.push_back(frd_csv_point(v, cols, file + ":" + std::to_string(ln)));
  }
  if (f.points.empty()) throw InputError(file + ": no data rows");
  std::stable_sort(f.points.begin(), f.points.end(),
                   [](const FrdPoint& a, const FrdPoint& b) { return a.w < b.w; });
  return f;
}

FitInput read_tfns_deck(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file + ": cannot open for reading");
  FitInput r;
  r.frd.source = file;
  r.frd.pair = "E1:E2";
  std::string line;
  int ln = 0, group = 0;
  double last_w = 0;
  while (std::getline(in, line)) {
    ++ln;
    const std::string where = file + ":" + std::to_string(ln);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const char flag = line.empty() ? ' ' : line[0];
    if (flag == '*') {
      if (++group == 2) break;
      continue;
    }
    if (group == 0) {
      tfns_control_card(line, where, r);
      continue;
    }
    if (trim(line).empty()) continue;
    r.frd.points.push_back(tfns_data_card(line, where, last_w));
    last_w = r.frd.points.back().w;
  }
  if (group < 2)
    throw InputError(file +
                     ": the deck needs two groups each ended by a '*' card (control, then data)");
  if (r.frd.points.empty()) throw InputError(file + ": no frequency-response cards");
  return r;
}

FitInput read_fit_input(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file + ": cannot open for reading");
  // The first line that is neither blank nor a '#' comment decides the format (no TFNS card
  // begins with '#': column 1 holds B, P, R, H, D, M, C, O, Z or '*').
  std::string first;
  while (std::getline(in, first) && (trim(first).empty() || trim(first)[0] == '#')) {
  }
  std::string t = trim(first);
  if (t.empty()) {
    throw InputError(
        file +
        ": empty: expected fralab-frd/1 JSON, a CSV with a header (w or f_hz, and mag/phase_deg or "
        "re/im), or a TFNS card deck");
  }
  if (t[0] == '{') {
    FitInput r;
    r.frd = load_frd(file);
    return r;
  }
  if (t.find(',') != std::string::npos &&
      (t.find("w") != std::string::npos || t.find("f_hz") != std::string::npos)) {
    FitInput r;
    r.frd = read_frd_csv(file);
    return r;
  }
  FitInput r = read_tfns_deck(file);
  for (size_t i = 0; i < r.frd.points.size(); ++i)
    if (const std::string bad = frd_point_problem(r.frd.points[i]); !bad.empty())
      throw InputError(file + ": point " + std::to_string(i + 1) + ": " + bad);
  return r;
}

Tf delete_roots(const Tf& tf, const std::vector<std::string>& which) {
  Tf out = tf;
  std::vector<int> zdel, pdel;
  for (const auto& w : which) {
    int k = 0;
    try {
      k = std::stoi(w.substr(1));
    } catch (const std::exception&) {
      throw InputError("root deletion \"" + w + "\" must be like P03 or Z02");
    }
    auto& list = w[0] == 'P' ? pdel : zdel;
    const size_t n = w[0] == 'P' ? tf.poles.size() : tf.zeros.size();
    if ((w[0] != 'P' && w[0] != 'Z') || k < 1 || size_t(k) > n) {
      throw InputError("root deletion \"" + w + "\": the fit has " + std::to_string(n) +
                       (w[0] == 'P' ? " poles" : " zeros"));
    }
    list.push_back(k - 1);
  }
  auto erase = [](std::vector<Root>& v, std::vector<int> idx) {
    std::sort(idx.rbegin(), idx.rend());
    idx.erase(std::unique(idx.begin(), idx.end()), idx.end());
    for (int i : idx) v.erase(v.begin() + i);
  };
  erase(out.zeros, zdel);
  erase(out.poles, pdel);
  return out;
}

}  // namespace fralab
