#include "fralab/acquire/acquisition_summary.h"

namespace fralab {

Json acquisition_summary_to_json(const AcquisitionSummary& s) {
  Json j{{"run_id", s.run_id},
         {"engine_time_s", s.engine_time_s},
         {"wall_time_s", s.wall_time_s},
         {"speedup", s.speedup},
         {"blocks", s.blocks},
         {"first_block", s.first_block},
         {"samples", s.samples},
         {"excitation", to_string(s.excitation)},
         {"retransmissions", s.retransmissions},
         {"items_retransmitted", s.items_retransmitted},
         {"plant_clock", s.free_running ? "free" : "lockstep"}};
  if (s.adaptive) j["adaptive"] = *s.adaptive;
  if (s.free_running) {
    j["held_samples"] = s.held_samples;
    Json& r = j["repeated_steps"] = Json::array();
    for (const RepeatedStep& x : s.repeated_steps)
      r.push_back({{"step", x.step}, {"frequency_hz", x.frequency_hz}, {"round", x.round}});
  }
  return j;
}

AcquisitionSummary acquisition_summary_from_json(const Json& j, const JsonWhere& where) {
  json_require_object(j, where);
  AcquisitionSummary s;
  auto integer = [&](const char* key, int64_t fallback) {
    return j.contains(key) ? json_integer(j.at(key), where / key) : fallback;
  };
  s.run_id = json_string_member(j, where, "run_id");
  s.samples = json_integer(json_member(j, where, "samples"), where / "samples");
  s.engine_time_s = json_number_member(j, where, "engine_time_s", 0.0);
  s.wall_time_s = json_number_member(j, where, "wall_time_s", 0.0);
  s.speedup = json_number_member(j, where, "speedup", 0.0);
  s.blocks = integer("blocks", 0);
  s.first_block = integer("first_block", 0);
  if (j.contains("excitation"))
    s.excitation = excitation_from_string(json_string(j.at("excitation"), where / "excitation"));
  s.retransmissions = integer("retransmissions", 0);
  s.items_retransmitted = integer("items_retransmitted", 0);
  if (j.contains("plant_clock")) {
    const std::string clock = json_string(j.at("plant_clock"), where / "plant_clock");
    if (clock != "free" && clock != "lockstep")
      json_fail(where / "plant_clock", "\"" + clock + "\": free or lockstep");
    s.free_running = clock == "free";
  }
  if (j.contains("adaptive")) {
    json_require_object(j.at("adaptive"), where / "adaptive");
    s.adaptive = j.at("adaptive");
  }
  s.held_samples = integer("held_samples", 0);
  const Json& repeated = json_array_member(j, where, "repeated_steps", true);
  for (size_t i = 0; i < repeated.size(); ++i) {
    const Json& x = repeated[i];
    const JsonWhere at = where / "repeated_steps" / i;
    json_require_object(x, at);
    s.repeated_steps.push_back({int(json_integer(json_member(x, at, "step"), at / "step")),
                                json_number_member(x, at, "frequency_hz"),
                                int(json_integer(json_member(x, at, "round"), at / "round"))});
  }
  return s;
}

}  // namespace fralab
