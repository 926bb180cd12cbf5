#include "fralab/exchange/time_series.h"

#include <sndfile.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "fralab/core/error.h"
#include "fralab/core/text.h"
#include "fralab/exchange/mat_file.h"

namespace fralab {

void SeriesReadOptions::validate() const {
  if (time_column.empty()) throw InputError("--time: a column name is needed");
  if (!wav_scale.empty() && wav_scale.size() != wav_channels.size())
    throw InputError("--scale: " + std::to_string(wav_scale.size()) + " values for " +
                     std::to_string(wav_channels.size()) + " channels");
  if (!wav_offset.empty() && wav_offset.size() != wav_channels.size())
    throw InputError("--offset: " + std::to_string(wav_offset.size()) + " values for " +
                     std::to_string(wav_channels.size()) + " channels");
  for (double s : wav_scale)
    if (!std::isfinite(s) || s == 0.0) throw InputError("--scale: each scale finite and nonzero");
  for (double s : wav_offset)
    if (!std::isfinite(s)) throw InputError("--offset: each offset finite");
}

namespace {

std::string trim(std::string s) {
  const char* ws = " \t\r\"";
  s.erase(0, s.find_first_not_of(ws));
  const size_t e = s.find_last_not_of(ws);
  s.erase(e == std::string::npos ? 0 : e + 1);
  return s;
}

std::vector<std::string> fields_of(const std::string& line) {
  std::vector<std::string> out;
  size_t a = 0;
  while (true) {
    const size_t b = line.find(',', a);
    out.push_back(trim(line.substr(a, b == std::string::npos ? std::string::npos : b - a)));
    if (b == std::string::npos) break;
    a = b + 1;
  }
  return out;
}

// Splits raw columns into the time column and the channels.
RawSeries take_time(RawSeries raw, const std::string& time_column, const std::string& path) {
  for (size_t i = 0; i < raw.names.size(); ++i) {
    if (raw.names[i] != time_column) continue;
    raw.time = std::move(raw.columns[i]);
    raw.columns.erase(raw.columns.begin() + long(i));
    if (raw.units.size() > i) raw.units.erase(raw.units.begin() + long(i));
    raw.names.erase(raw.names.begin() + long(i));
    if (raw.names.empty()) throw InputError(path + ": no channel beside the time column");
    return raw;
  }
  std::string have;
  for (const auto& n : raw.names) have += (have.empty() ? "" : ", ") + n;
  throw InputError(path + ": no time column '" + time_column + "' (columns: " + have +
                   "; --time names it)");
}

}  // namespace

RawSeries read_csv_series(const std::string& path, const SeriesReadOptions& o) {
  o.validate();
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot be read");
  RawSeries raw;
  raw.source = path;
  std::vector<std::string> units;
  std::string line;
  int lineno = 0;
  bool header = false;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (trim(line).empty()) continue;
    if (line[0] == '#') {
      const std::string c = trim(line.substr(1));
      if (!header && c.rfind("units:", 0) == 0) units = fields_of(c.substr(6));
      continue;
    }
    std::vector<std::string> f = fields_of(line);
    if (!header) {
      for (size_t i = 0; i < f.size(); ++i) {
        if (f[i].empty())
          throw InputError(path + ":" + std::to_string(lineno) + ": column " +
                           std::to_string(i + 1) + " of the header has no name");
        for (size_t k = 0; k < i; ++k)
          if (f[k] == f[i])
            throw InputError(path + ":" + std::to_string(lineno) + ": column '" + f[i] +
                             "' named twice");
      }
      raw.names = f;
      raw.columns.resize(f.size());
      header = true;
      raw.first_row_line = 0;
      continue;
    }
    if (raw.first_row_line == 0) raw.first_row_line = lineno;
    if (f.size() != raw.names.size())
      throw InputError(path + ":" + std::to_string(lineno) + ": " + std::to_string(f.size()) +
                       " fields, the header names " + std::to_string(raw.names.size()));
    for (size_t i = 0; i < f.size(); ++i) {
      double v = 0.0;
      const char* b = f[i].data();
      const char* e = b + f[i].size();
      auto [p, ec] = std::from_chars(b, e, v);
      if (f[i] == "NaN" || f[i] == "nan" || f[i] == "NA")
        v = std::nan("");
      else if (ec != std::errc() || p != e)
        throw InputError(path + ":" + std::to_string(lineno) + ": column '" + raw.names[i] +
                         "': '" + f[i] + "' is not a number");
      raw.columns[i].push_back(v);
    }
  }
  if (!header) throw InputError(path + ": no header row (the column names)");
  if (raw.columns.empty() || raw.columns[0].empty()) throw InputError(path + ": no data rows");
  // Units in the "# units:" comment are per header column, the time column included.
  if (units.size() == raw.names.size()) raw.units = units;
  return take_time(std::move(raw), o.time_column, path);
}

RawSeries read_wav_series(const std::string& path, const SeriesReadOptions& o) {
  o.validate();
  if (o.wav_channels.empty())
    throw InputError(path + ": a WAV file names no channels: give them in order (--channels)");
  SF_INFO info{};
  std::unique_ptr<SNDFILE, int (*)(SNDFILE*)> f(sf_open(path.c_str(), SFM_READ, &info), sf_close);
  if (!f) throw InputError(path + ": " + sf_strerror(nullptr));
  if (size_t(info.channels) != o.wav_channels.size())
    throw InputError(path + ": " + std::to_string(info.channels) + " channels in the file, " +
                     std::to_string(o.wav_channels.size()) + " named (--channels)");
  if (info.frames <= 0) throw InputError(path + ": no samples");
  std::vector<double> buf(size_t(info.frames) * size_t(info.channels));
  const sf_count_t got = sf_readf_double(f.get(), buf.data(), info.frames);
  if (got != info.frames)
    throw InputError(path + ": " + std::to_string(got) + " of " + std::to_string(info.frames) +
                     " frames read (a cut file?)");
  RawSeries raw;
  raw.source = path;
  raw.sample_rate_hz = info.samplerate;
  raw.names = o.wav_channels;
  raw.columns.assign(raw.names.size(), std::vector<double>(size_t(info.frames)));
  for (size_t c = 0; c < raw.names.size(); ++c) {
    const double scale = o.wav_scale.empty() ? 1.0 : o.wav_scale[c];
    const double offset = o.wav_offset.empty() ? 0.0 : o.wav_offset[c];
    for (sf_count_t k = 0; k < info.frames; ++k)
      raw.columns[c][size_t(k)] = scale * buf[size_t(k) * raw.names.size() + c] + offset;
  }
  return raw;
}

RawSeries read_mat_series(const std::string& path, const SeriesReadOptions& o) {
  o.validate();
  std::vector<std::string> skipped, not_vectors;
  auto vectors = read_mat_vectors(path, &not_vectors);
  for (const auto& k : not_vectors)
    if (k != "units" && k != "fralab") skipped.push_back(k);  // write_mat_series's own
  RawSeries raw;
  raw.source = path;
  size_t n = 0;
  for (const auto& [name, v] : vectors)
    if (name == o.time_column) n = v.size();
  if (n == 0) {
    std::string have;
    for (const auto& [name, v] : vectors) have += (have.empty() ? "" : ", ") + name;
    throw InputError(path + ": no time vector '" + o.time_column +
                     "' (vectors: " + (have.empty() ? "none" : have) + "; --time names it)");
  }
  for (auto& [name, v] : vectors) {
    if (v.size() != n) {
      if (name != "units" && name != "fralab") skipped.push_back(name);  // write_mat_series's
      continue;
    }
    raw.names.push_back(name);
    raw.columns.push_back(std::move(v));
  }
  if (!skipped.empty()) {
    std::string s;
    for (const auto& k : skipped) s += (s.empty() ? "" : ", ") + k;
    std::fprintf(stderr, "fralab: %s: not channels (not a real vector of %zu samples): %s\n",
                 path.c_str(), n, s.c_str());
  }
  return take_time(std::move(raw), o.time_column, path);
}

RawSeries read_series(const std::string& path, const SeriesReadOptions& o) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".csv") return read_csv_series(path, o);
  if (ext == ".wav") return read_wav_series(path, o);
  if (ext == ".mat") return read_mat_series(path, o);
  throw InputError(path + ": not a time series fralab reads (.csv, .wav, .mat)");
}

TimeSeries to_time_series(const RawSeries& raw, double sample_rate_hz) {
  const std::string& path = raw.source;
  double fs = sample_rate_hz;
  if (!raw.time.empty() && fs <= 0 && raw.time.size() >= 2) {
    // No schedule to say it: the time column's mean rate, a whole number of Hz when that close.
    const double span = raw.time.back() - raw.time.front();
    const double est = span > 0 ? double(raw.time.size() - 1) / span : 0.0;
    fs = std::abs(est - std::round(est)) <= 1e-6 * est ? std::round(est) : est;
  }
  if (raw.time.empty()) {
    if (fs <= 0)
      fs = raw.sample_rate_hz;
    else if (raw.sample_rate_hz > 0 && std::abs(raw.sample_rate_hz - fs) > 1e-9 * fs)
      throw InputError(path + ": sampled at " + lossless(raw.sample_rate_hz) +
                       " Hz, the schedule at " + lossless(fs) + " Hz");
  }
  if (!(fs > 0) || !std::isfinite(fs))
    throw InputError(path + ": no sample rate (the schedule's sample_rate_hz)");
  TimeSeries s;
  s.source = path;
  s.sample_rate_hz = fs;
  s.channels = raw.names;
  s.units =
      raw.units.size() == raw.names.size() ? raw.units : std::vector<std::string>(raw.names.size());
  const size_t n = raw.columns.empty() ? 0 : raw.columns[0].size();
  if (n == 0) throw InputError(path + ": no samples");
  auto row = [&](size_t k) {
    return raw.first_row_line > 0 ? "line " + std::to_string(raw.first_row_line + k)
                                  : "sample " + std::to_string(k);
  };
  if (!raw.time.empty()) {
    auto on_clock = [&](size_t k, int64_t* sample) {
      const double t = raw.time[k];
      const double x = t * fs;
      if (!std::isfinite(t) || !(std::abs(x) < 9.0e15))  // sample numbers exact in a double
        throw InputError(path + ": " + row(k) + ": time " + lossless(t) + " s is out of range");
      *sample = std::llround(x);
      return std::abs(x - double(*sample)) <= kClockTolerance;
    };
    int64_t n0 = 0;
    if (!on_clock(0, &n0))
      throw InputError(path + ": " + row(0) + ": t = " + lossless(raw.time[0]) +
                       " s is not on the " + lossless(fs) + " Hz sample clock");
    s.start_sample = n0;
    for (size_t k = 1; k < n; ++k) {
      int64_t nk = 0;
      const bool on = on_clock(k, &nk);
      if (raw.time[k] <= raw.time[k - 1])
        throw InputError(path + ": " + row(k) + ": time goes back or stands still (t = " +
                         lossless(raw.time[k]) + " s after " + lossless(raw.time[k - 1]) + " s)");
      if (!on)
        throw InputError(path + ": " + row(k) + ": t = " + lossless(raw.time[k]) +
                         " s is off the " + lossless(fs) + " Hz sample clock");
      if (nk != n0 + int64_t(k))
        throw InputError(path + ": " + row(k) + ": a gap of " +
                         std::to_string(nk - n0 - int64_t(k)) +
                         " samples before t = " + lossless(raw.time[k]) + " s");
    }
  }
  s.n_samples = int64_t(n);
  s.samples.reserve(n * raw.columns.size());
  for (size_t c = 0; c < raw.columns.size(); ++c) {
    if (raw.columns[c].size() != n)
      throw InputError(path + ": channel '" + raw.names[c] + "' has " +
                       std::to_string(raw.columns[c].size()) + " samples, not " +
                       std::to_string(n));
    for (size_t k = 0; k < n; ++k) {
      const double v = raw.columns[c][k];
      if (!std::isfinite(v))
        throw InputError(
            path + ": " + row(k) + " (t = " + lossless(double(s.start_sample + int64_t(k)) / fs) +
            " s): channel '" + raw.names[c] + "' is " + (std::isnan(v) ? "NaN" : "infinite"));
      s.samples.push_back(v);
    }
  }
  return s;
}

void write_csv_series(const std::string& path, const TimeSeries& s) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "w"), std::fclose);
  if (!f) throw InputError(path + ": cannot be written");
  std::fprintf(f.get(), "# fralab time series: t in seconds on the %s Hz sample clock\n",
               lossless(s.sample_rate_hz).c_str());
  std::string units = "s", header = "t";
  for (size_t c = 0; c < s.channels.size(); ++c) {
    units += "," + (c < s.units.size() ? s.units[c] : std::string());
    header += "," + s.channels[c];
  }
  std::fprintf(f.get(), "# units: %s\n%s\n", units.c_str(), header.c_str());
  std::string line;
  for (int64_t k = 0; k < s.n_samples; ++k) {
    line = lossless(double(s.start_sample + k) / s.sample_rate_hz);
    for (size_t c = 0; c < s.channels.size(); ++c) line += "," + lossless(s.at(c, k));
    line += '\n';
    std::fputs(line.c_str(), f.get());
  }
  if (std::fflush(f.get()) != 0) throw InputError(path + ": write failed");
}

void write_mat_series(const std::string& path, const TimeSeries& s) {
  std::vector<std::pair<std::string, MatValue>> vars;
  std::vector<double> t(size_t(s.n_samples));
  for (int64_t k = 0; k < s.n_samples; ++k)
    t[size_t(k)] = double(s.start_sample + k) / s.sample_rate_hz;
  vars.emplace_back("t", MatValue::column(t));
  MatValue units = MatValue::structure();
  units.add("t", MatValue::str("s"));
  for (size_t c = 0; c < s.channels.size(); ++c) {
    if (!is_mat_name(s.channels[c]) || s.channels[c] == "t" || s.channels[c] == "units" ||
        s.channels[c] == "fralab")
      throw InputError(path + ": channel '" + s.channels[c] + "' cannot be a .mat variable name");
    vars.emplace_back(s.channels[c], MatValue::column(std::vector<double>(
                                         s.samples.begin() + long(c * size_t(s.n_samples)),
                                         s.samples.begin() + long((c + 1) * size_t(s.n_samples)))));
    units.add(s.channels[c], MatValue::str(c < s.units.size() ? s.units[c] : ""));
  }
  vars.emplace_back("units", units);
  MatValue info = MatValue::structure();
  info.add("sample_rate_hz", MatValue::scalar(s.sample_rate_hz));
  info.add("channels", MatValue::str_list(s.channels));
  vars.emplace_back("fralab", info);
  write_mat_file(path, vars);
}

}  // namespace fralab
