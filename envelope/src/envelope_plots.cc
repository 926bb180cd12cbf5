// The envelope's pictures (gnuplot): the root migration (each state's root against the scheduling
// variable, with its sigma; the slow states dashed, with their paths' range) and the findings
// across points with their laws.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fralab/analyze/bode_plot.h"
#include "fralab/core/text.h"
#include "fralab/envelope/envelope.h"

namespace fs = std::filesystem;

namespace fralab {

namespace {

constexpr size_t kMaxTracks = 12;  // the plot stays readable; the table has every state

std::string quoted(const std::string& s) {  // a gnuplot single-quoted string
  std::string r = "'";
  for (char c : s) r += c == '\'' ? std::string("''") : std::string(1, c);
  return r + "'";
}

// |root| in rad/s: 1/tau for a real pole, wn for a pair.
double magnitude(const TrackValue& v) { return v.pair ? v.value : 1 / v.value; }

std::string law_expression(const FindingLaw& f) {
  const std::string a = lossless(f.a), b = lossless(f.b);
  if (f.law == "linear") return a + " + (" + b + ") * x";
  if (f.law == "power") return a + " * x ** (" + b + ")";
  return a;
}

// The tracks drawn: those at two points or more, the longest first.
std::vector<const StateTrack*> plotted_tracks(const EnvelopeReport& r) {
  std::vector<const StateTrack*> t;
  for (const StateTrack& s : r.tracks)
    if (s.values.size() >= 2) t.push_back(&s);
  std::stable_sort(t.begin(), t.end(), [](const StateTrack* a, const StateTrack* b) {
    return a->values.size() > b->values.size();
  });
  if (t.size() > kMaxTracks) t.resize(kMaxTracks);
  return t;
}

// The plots' data: roots.dat (each plotted track's |root| and its sigma per point, then the slow
// states' 1/mean tau and their paths' range as 1/hi, 1/lo) and findings.dat (each finding's
// value and sigma per point), one gnuplot index each.
void write_plot_data(const EnvelopeReport& r, const std::vector<const StateTrack*>& tracks,
                     const std::string& pd) {
  {
    std::ofstream d(pd + "/roots.dat");
    for (const StateTrack* t : tracks) {
      d << "# " << t->label << "\n";
      for (const TrackValue& v : t->values) {
        const double m = magnitude(v);
        d << lossless(v.x) << " " << lossless(m) << " "
          << lossless(v.rel_sigma > 0 ? v.rel_sigma * m : 0) << "\n";
      }
      d << "\n\n";
    }
    for (const SlowState& t : r.slow_states) {
      d << "# slow state " << t.label << "\n";
      for (const auto& v : t.values)
        d << lossless(v.x) << " " << lossless(1 / v.tau_s) << " " << lossless(1 / v.hi) << " "
          << lossless(1 / v.lo) << "\n";
      d << "\n\n";
    }
  }
  std::ofstream d(pd + "/findings.dat");
  for (const FindingLaw& f : r.findings) {
    d << "# " << f.cause << " " << f.parameter << "\n";
    for (const auto& v : f.values)
      d << lossless(v.x) << " " << lossless(v.value) << " " << lossless(std::max(v.sigma, 0.0))
        << "\n";
    d << "\n\n";
  }
}

// The root migration plot's gnuplot lines (the terminal and output already set).
void roots_plot(std::ostringstream& gp, const EnvelopeReport& r,
                const std::vector<const StateTrack*>& tracks, const std::string& pd) {
  if (tracks.empty() && r.slow_states.empty()) {
    gp << "set label 'no state at two points or more' at graph 0.3, 0.5\nplot 1/0 notitle\n";
    return;
  }
  gp << "plot ";
  for (size_t i = 0; i < tracks.size(); ++i)
    gp << (i ? ", \\\n  " : "") << quoted(pd + "/roots.dat") << " index " << i
       << " using 1:2:3 with yerrorlines title "
       << quoted(tracks[i]->label + (tracks[i]->pair ? " (pair)" : ""));
  for (size_t i = 0; i < r.slow_states.size(); ++i)
    gp << (i + tracks.size() ? ", \\\n  " : "") << quoted(pd + "/roots.dat") << " index "
       << tracks.size() + i << " using 1:2:3:4 with yerrorlines lw 3 dt 2 title "
       << quoted("slow state " + r.slow_states[i].label + " (mean, range over paths)");
  gp << "\n";
}

// The findings' multiplot (rows x cols panels, each finding's values and its law) over x range
// [xlo, xhi].
void findings_plot(std::ostringstream& gp, const EnvelopeReport& r, size_t rows, size_t cols,
                   double xlo, double xhi, const std::string& pd) {
  gp << "set multiplot layout " << rows << "," << cols
     << " title 'Findings across points with their laws'\nset grid\nset xrange [" << lossless(xlo)
     << ":" << lossless(xhi) << "]\nset key off\n";
  for (size_t i = 0; i < r.findings.size(); ++i) {
    const FindingLaw& f = r.findings[i];
    std::string where = f.input + (f.output.empty() ? "" : " -> " + f.output);
    gp << "set title " << quoted(f.cause + " " + where + ": " + f.parameter + " (" + f.law + ")")
       << " font ',9'\nplot " << quoted(pd + "/findings.dat") << " index " << i
       << " using 1:2:3 with yerrorbars pt 7, " << law_expression(f) << " with lines lw 2\n";
  }
  gp << "unset multiplot\nset output\n";
}

}  // namespace

bool render_envelope_plots(const EnvelopeReport& r, const std::string& dir) {
  const std::string pd = dir + "/plots";
  fs::create_directories(pd);
  const auto tracks = plotted_tracks(r);
  write_plot_data(r, tracks, pd);
  const size_t nf = r.findings.size();
  const size_t cols = nf < 3 ? std::max<size_t>(nf, 1) : 3, rows = (nf + cols - 1) / cols;
  double xlo = r.points.empty() ? 0 : r.points.front().x;
  double xhi = r.points.empty() ? 1 : r.points.back().x;
  const double pad = 0.05 * std::max(xhi - xlo, 1.0);
  xlo -= pad, xhi += pad;
  std::ostringstream gp;
  for (const bool svg : {false, true}) {
    const std::string ext = svg ? "svg" : "png";
    auto term = [&](size_t height) {
      return std::string(svg ? "svg" : "pngcairo") + " size 900," + std::to_string(height) +
             (svg ? " dynamic noenhanced font 'sans,11'" : " noenhanced font 'sans,10'");
    };
    gp << "reset\nset terminal " << term(560) << "\nset output " << quoted(pd + "/roots." + ext)
       << "\nset title 'Root migration: each state against " << r.schedule_by
       << "'\nset logscale y\nset grid\nset xrange [" << lossless(xlo) << ":" << lossless(xhi)
       << "]\nset xlabel " << quoted(r.schedule_by) << "\nset ylabel '|root| (rad/s)'\n"
       << "set key outside right font ',8'\n";
    roots_plot(gp, r, tracks, pd);
    gp << "set output\nreset\nset terminal " << term(220 * std::max<size_t>(rows, 1))
       << "\nset output " << quoted(pd + "/findings." + ext) << "\n";
    if (nf == 0) {
      gp << "set label 'no findings' at graph 0.4, 0.5\nplot 1/0 notitle\nset output\n";
      continue;
    }
    findings_plot(gp, r, rows, cols, xlo, xhi, pd);
  }
  std::ofstream(pd + "/envelope.gp") << gp.str();
  return run_gnuplot(pd + "/envelope.gp");
}

}  // namespace fralab
