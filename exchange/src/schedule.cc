#include "fralab/exchange/schedule.h"

#include <cmath>

#include "fralab/core/error.h"
#include "fralab/core/measurement_chain.h"

namespace fralab {

namespace {

Json event_to_json(const StatusEvent& e) {
  Json j{{"seq", e.seq},
         {"sample", e.sample},
         {"excitation", status_word(e.excitation)},
         {"state", to_string(e.state)},
         {"step", e.step},
         {"n_steps", e.n_steps},
         {"frequency_hz", e.frequency_hz},
         {"ref_phase_rad", e.ref_phase_rad},
         {"n_cycles", e.n_cycles},
         {"n_samples", e.n_samples},
         {"inputs", e.inputs},
         {"amplitudes", e.amplitudes}};
  if (!e.message.empty()) j["message"] = e.message;
  if (e.measurement_chain) j["measurement_chain"] = chain_to_json(*e.measurement_chain);
  if (e.excitation == Excitation::kMultisine) {
    j["period_samples"] = e.period_samples;
    j["lines"] = e.lines;
    j["line_input"] = e.line_input;
  }
  return j;
}

int64_t integer_member(const Json& o, const JsonWhere& w, const std::string& key, double dflt) {
  const double v = json_number_member(o, w, key, dflt);
  if (v != std::floor(v) || std::abs(v) > 9.0e15)
    throw InputError((w / key).str() + ": " + std::to_string(v) + " is not a whole number");
  return int64_t(v);
}

StatusEvent event_from_json(const Json& o, const JsonWhere& w, int index, double fs,
                            const std::string& run_id) {
  json_require_object(o, w);
  StatusEvent e;
  e.run_id = run_id;
  e.sample_rate_hz = fs;
  e.state = run_state_from_string(json_string_member(o, w, "state"));
  e.seq = integer_member(o, w, "seq", e.state == RunState::kStart ? -1.0 : double(index));
  e.sample = integer_member(o, w, "sample", 0.0);
  e.excitation = o.contains("excitation")
                     ? excitation_from_status_word(json_string_member(o, w, "excitation"))
                     : Excitation::kStepped;
  e.step = int(integer_member(o, w, "step", 0.0));
  e.n_steps = int(integer_member(o, w, "n_steps", 0.0));
  e.frequency_hz = json_number_member(o, w, "frequency_hz", 0.0);
  e.ref_phase_rad = json_number_member(o, w, "ref_phase_rad", 0.0);
  e.n_cycles = int(integer_member(o, w, "n_cycles", 0.0));
  e.n_samples = integer_member(o, w, "n_samples", 0.0);
  if (e.frequency_hz < 0 || e.frequency_hz > fs / 2)
    throw InputError((w / "frequency_hz").str() + ": " + std::to_string(e.frequency_hz) +
                     " Hz is outside 0 .. half the sample rate");
  if (e.n_samples < 0) throw InputError((w / "n_samples").str() + ": negative");
  if (o.contains("inputs")) {
    const Json& in = json_array_member(o, w, "inputs");
    for (size_t i = 0; i < in.size(); ++i) {
      if (!in[i].is_string())
        throw InputError((w / "inputs" / i).str() + ": an input name (text) is needed");
      e.inputs.push_back(in[i].get<std::string>());
    }
  }
  if (o.contains("amplitudes")) {
    const Json& a = json_array_member(o, w, "amplitudes");
    for (size_t i = 0; i < a.size(); ++i) {
      const double v = json_number(a[i], (w / "amplitudes" / i));
      if (v < 0) throw InputError((w / "amplitudes" / i).str() + ": a peak amplitude >= 0");
      e.amplitudes.push_back(v);
    }
  }
  if (e.amplitudes.size() != e.inputs.size())
    throw InputError(w.str() + ": " + std::to_string(e.amplitudes.size()) + " amplitudes for " +
                     std::to_string(e.inputs.size()) + " inputs");
  if (o.contains("message")) e.message = json_string_member(o, w, "message");
  // The chain as a key of its own, or as the message of a schedule written before it had one.
  if (o.contains("measurement_chain"))
    e.measurement_chain = chain_from_json(o["measurement_chain"], w / "measurement_chain");
  else
    e.measurement_chain = chain_from_message(e.message, (w / "message").str());
  if (e.excitation == Excitation::kMultisine) {
    e.period_samples = int(integer_member(o, w, "period_samples", 0.0));
    for (const char* key : {"lines", "line_input"}) {
      if (!o.contains(key)) continue;
      const Json& a = json_array_member(o, w, key);
      std::vector<int>& dst = std::string(key) == "lines" ? e.lines : e.line_input;
      for (size_t i = 0; i < a.size(); ++i) {
        const double v = json_number(a[i], (w / key / i));
        if (v != std::floor(v) || v < 0 || v > 1e9)
          throw InputError((w / key / i).str() + ": a whole number >= 0");
        dst.push_back(int(v));
      }
    }
    if (e.lines.size() != e.line_input.size())
      throw InputError(w.str() + ": lines and line_input differ in length");
    for (size_t i = 0; i < e.line_input.size(); ++i)
      if (size_t(e.line_input[i]) >= e.inputs.size())
        throw InputError((w / "line_input" / i).str() + ": no input " +
                         std::to_string(e.line_input[i]));
  }
  return e;
}

}  // namespace

Json schedule_to_json(const Schedule& s) {
  Json j{{"format", kScheduleFormat},
         {"sample_rate_hz", s.sample_rate_hz},
         {"run_id", s.run_id},
         {"events", Json::array()}};
  for (const auto& e : s.events) j["events"].push_back(event_to_json(e));
  return j;
}

Schedule schedule_from_json(const Json& j, const std::string& source) {
  const JsonWhere w{source, ""};
  json_require_object(j, w);
  const std::string format = json_string_member(j, w, "format");
  if (format != kScheduleFormat)
    throw InputError((w / "format").str() + ": '" + format + "', expected " + kScheduleFormat);
  Schedule s;
  s.sample_rate_hz = json_number_member(j, w, "sample_rate_hz");
  if (!(s.sample_rate_hz > 0) || s.sample_rate_hz > 1e9)
    throw InputError((w / "sample_rate_hz").str() + ": a rate in Hz > 0 is needed");
  s.run_id = j.contains("run_id") ? json_string_member(j, w, "run_id") : "imported";
  if (s.run_id.empty()) s.run_id = "imported";
  const Json& events = json_array_member(j, w, "events");
  for (size_t i = 0; i < events.size(); ++i) {
    s.events.push_back(
        event_from_json(events[i], (w / "events" / i), int(i), s.sample_rate_hz, s.run_id));
    if (i > 0 && s.events[i].sample < s.events[i - 1].sample)
      throw InputError((w / "events" / i).str() + ": sample " + std::to_string(s.events[i].sample) +
                       " before the previous event's " + std::to_string(s.events[i - 1].sample));
  }
  if (s.events.empty()) throw InputError((w / "events").str() + ": no events");
  return s;
}

Schedule load_schedule(const std::string& file) {
  return schedule_from_json(json_load_file(file), file);
}

}  // namespace fralab
