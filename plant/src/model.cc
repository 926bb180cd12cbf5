#include "fralab/plant/model.h"

#include <set>

#include "fralab/core/pair_id.h"
#include "fralab/core/text.h"
#include "fralab/plant/state_space.h"

namespace fralab {

std::string unit_kind(const std::string& u) {
  static const std::map<std::string, std::string> kinds = {{"lb/hr", "mass_flow"},
                                                           {"lb/h", "mass_flow"},
                                                           {"kg/s", "mass_flow"},
                                                           {"in^2", "area"},
                                                           {"in2", "area"},
                                                           {"m^2", "area"},
                                                           {"rpm", "speed"},
                                                           {"rad/s", "speed"},
                                                           {"psi", "pressure"},
                                                           {"psia", "pressure"},
                                                           {"kPa", "pressure"},
                                                           {"Pa", "pressure"},
                                                           {"degR", "temperature"},
                                                           {"R", "temperature"},
                                                           {"K", "temperature"},
                                                           {"psi/psi", "dimensionless"},
                                                           {"1", "dimensionless"},
                                                           {"", "dimensionless"},
                                                           {"nondimensional", "dimensionless"},
                                                           {"fraction", "dimensionless"},
                                                           {"%", "dimensionless"},
                                                           {"pct", "dimensionless"}};
  auto it = kinds.find(u);
  return it == kinds.end() ? std::string("unknown") : it->second;
}

std::string channel_kind(const std::string& n) {
  static const std::map<std::string, std::string> kinds = {
      {"Wf", "mass_flow"},       {"A8", "area"},        {"BLD", "dimensionless"},
      {"IGV", "dimensionless"},  {"N", "speed"},        {"P3", "pressure"},
      {"P5", "pressure"},        {"PBLD", "pressure"},  {"dPfn", "pressure"},
      {"DPP3", "dimensionless"}, {"T4", "temperature"}, {"T5", "temperature"}};
  auto it = kinds.find(n);
  return it == kinds.end() ? std::string() : it->second;
}

static void check_units(const std::string& name, const std::string& units, const JsonWhere& w) {
  const std::string want = channel_kind(name);
  if (want.empty()) return;
  const std::string got = unit_kind(units);
  if (got == "unknown") {
    json_fail(w,
              "unknown units \"" + units + "\" for " + name + " (expected units of " + want + ")");
  }
  if (got != want) {
    json_fail(w, "units \"" + units + "\" are " + got + ", but " + name + " is a " + want +
                     " channel: give it units of " + want);
  }
}

static void check_name(const std::string& name, const JsonWhere& w) {
  if (name.empty()) json_fail(w, "a channel name must not be empty");
  for (char c : name) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) {
      json_fail(w, "channel name \"" + name + "\" may hold only letters, digits and '_'");
    }
  }
  if (commanded_input(name) || name.rfind("ref_", 0) == 0) {
    json_fail(w,
              "channel name \"" + name + "\" is reserved (u_* are commands, ref_* the reference)");
  }
}

namespace {
constexpr std::pair<NonlinearityKind, const char*> kNonlinearityWords[] = {
    {NonlinearityKind::kDeadband, "deadband"},
    {NonlinearityKind::kHysteresis, "hysteresis"},
    {NonlinearityKind::kRateLimit, "rate_limit"},
    {NonlinearityKind::kSaturation, "saturation"},
};
}  // namespace

const char* to_string(NonlinearityKind k) { return enum_word(kNonlinearityWords, k); }

std::optional<NonlinearityKind> nonlinearity_kind_from_word(const std::string& word) {
  return enum_from_word(kNonlinearityWords, word);
}

static NonlinearitySpec nonlinearity_from_json(const Json& j, const JsonWhere& w,
                                               std::vector<std::string>* warnings) {
  NonlinearitySpec nl;
  const std::string type = json_string_member(j, w, "type");
  const std::optional<NonlinearityKind> kind = nonlinearity_kind_from_word(type);
  if (!kind)
    json_fail(w / "type", "unknown nonlinearity type \"" + type +
                              "\" (known: deadband, hysteresis, rate_limit, saturation)");
  nl.kind = *kind;
  if (has_width(nl.kind)) {
    json_unknown_members(j, w, {"type", "width"}, warnings);
    nl.width = json_number_member(j, w, "width");
    if (nl.width <= 0.0) json_fail(w / "width", "width must be > 0 (input units)");
  } else if (nl.kind == NonlinearityKind::kRateLimit) {
    json_unknown_members(j, w, {"type", "rate"}, warnings);
    nl.rate = json_number_member(j, w, "rate");
    if (nl.rate <= 0.0) json_fail(w / "rate", "rate must be > 0 (input units per second)");
  } else {
    json_unknown_members(j, w, {"type", "min", "max"}, warnings);
    nl.min = json_number_member(j, w, "min");
    nl.max = json_number_member(j, w, "max");
    if (!(nl.min < nl.max)) json_fail(w, "saturation needs min < max");
  }
  return nl;
}

// The operating point's speed and steady state, where the file gives one.
static void parse_operating_point(const Json& doc, const JsonWhere& root, Model& m) {
  if (!doc.contains("operating_point")) return;
  const Json& op = doc["operating_point"];
  JsonWhere w = root / "operating_point";
  json_require_object(op, w);
  m.operating_point_extra = json_unknown_members(op, w, {"speed_pct", "steady_state"}, &m.warnings);
  m.speed_pct = json_number_member(op, w, "speed_pct", 0.0);
  if (op.contains("steady_state")) {
    const Json& ss = op["steady_state"];
    json_require_object(ss, w / "steady_state");
    for (auto it = ss.begin(); it != ss.end(); ++it) {
      m.steady_state[it.key()] = json_number(it.value(), w / "steady_state" / it.key());
    }
  }
}

// A channel's name, checked and not yet taken (names holds the channels read so far), and units
// of the channel's kind.
static void read_channel_name(const Json& j, const JsonWhere& w, std::set<std::string>& names,
                              std::string& name, std::string& units) {
  name = json_string_member(j, w, "name");
  check_name(name, w / "name");
  if (!names.insert(name).second) json_fail(w / "name", "duplicate channel name \"" + name + "\"");
  units = json_string_member(j, w, "units");
  check_units(name, units, w / "units");
}

static ModelInput model_input_from_json(const Json& j, const JsonWhere& w,
                                        std::set<std::string>& names,
                                        std::vector<std::string>* warn) {
  json_require_object(j, w);
  ModelInput in;
  in.extra = json_unknown_members(j, w,
                                  {"name", "units", "full_scale", "actuator", "noise_rms",
                                   "test_amplitude_pct", "measurement_coupling", "faults"},
                                  warn);
  read_channel_name(j, w, names, in.name, in.units);
  in.full_scale = json_number_member(j, w, "full_scale");
  if (in.full_scale <= 0.0) json_fail(w / "full_scale", "full_scale must be > 0 (input units)");
  in.noise_rms = json_number_member(j, w, "noise_rms", 0.0);
  if (in.noise_rms < 0.0) json_fail(w / "noise_rms", "noise_rms must be >= 0");
  in.test_amplitude_pct = json_number_member(j, w, "test_amplitude_pct", 0.0);
  if (in.test_amplitude_pct < 0.0 || in.test_amplitude_pct > 50.0) {
    json_fail(w / "test_amplitude_pct", "test_amplitude_pct must be in [0, 50] % of full scale");
  }
  if (j.contains("actuator")) {
    const Json& a = j["actuator"];
    JsonWhere wa = w / "actuator";
    json_require_object(a, wa);
    json_unknown_members(a, wa, {"tf", "nonlinearity"}, warn);
    if (a.contains("tf")) in.actuator = tf_from_json(a["tf"], wa / "tf", warn);
    const Json& nls = json_array_member(a, wa, "nonlinearity", true);
    for (size_t k = 0; k < nls.size(); ++k) {
      in.nonlinearity.push_back(nonlinearity_from_json(nls[k], wa / "nonlinearity" / k, warn));
    }
  }
  const Json& cs = json_array_member(j, w, "measurement_coupling", true);
  for (size_t k = 0; k < cs.size(); ++k) {
    JsonWhere wc = w / "measurement_coupling" / k;
    MeasurementCoupling c;
    c.output = json_string_member(cs[k], wc, "output");
    c.gain = json_number_member(cs[k], wc, "gain");
    in.measurement_coupling.push_back(c);
  }
  if (j.contains("faults")) in.faults = channel_faults_from_json(j["faults"], w / "faults", true);
  return in;
}

static ModelOutput model_output_from_json(const Json& j, const JsonWhere& w,
                                          std::set<std::string>& names,
                                          std::vector<std::string>* warn) {
  json_require_object(j, w);
  ModelOutput out;
  out.extra = json_unknown_members(j, w, {"name", "units", "noise_rms", "sensor", "faults"}, warn);
  read_channel_name(j, w, names, out.name, out.units);
  out.noise_rms = json_number_member(j, w, "noise_rms", 0.0);
  if (out.noise_rms < 0.0) json_fail(w / "noise_rms", "noise_rms must be >= 0");
  if (j.contains("sensor")) {
    const Json& s = j["sensor"];
    json_require_object(s, w / "sensor");
    json_unknown_members(s, w / "sensor", {"tf"}, warn);
    out.sensor = tf_from_json(json_member(s, w / "sensor", "tf"), w / "sensor" / "tf", warn);
  }
  if (j.contains("faults")) out.faults = channel_faults_from_json(j["faults"], w / "faults", false);
  return out;
}

// A path between an input and an output of m, the first between them.
static ModelPath model_path_from_json(const Json& j, const JsonWhere& w, const Model& m,
                                      std::vector<std::string>* warn) {
  json_require_object(j, w);
  ModelPath p;
  p.extra = json_unknown_members(j, w, {"output", "input", "tf"}, warn);
  p.output = json_string_member(j, w, "output");
  p.input = json_string_member(j, w, "input");
  if (m.output_index(p.output) < 0) json_fail(w / "output", "no output named \"" + p.output + "\"");
  if (m.input_index(p.input) < 0) json_fail(w / "input", "no input named \"" + p.input + "\"");
  if (m.path(p.output, p.input)) {
    json_fail(w, "a second path " + p.input + " -> " + p.output + " (one path per pair)");
  }
  p.tf = tf_from_json(json_member(j, w, "tf"), w / "tf", warn);
  return p;
}

// The names the channels give each other: a measurement coupling's output, a swap's other
// channel (and only one of the two lists a swap).
static void check_cross_references(const Model& m, const JsonWhere& root) {
  for (size_t i = 0; i < m.inputs.size(); ++i) {
    for (size_t k = 0; k < m.inputs[i].measurement_coupling.size(); ++k) {
      const auto& c = m.inputs[i].measurement_coupling[k];
      if (m.output_index(c.output) < 0) {
        json_fail(root / "inputs" / i / "measurement_coupling" / k / "output",
                  "no output named \"" + c.output + "\"");
      }
    }
  }
  auto check_swaps = [&](const std::string& name, const std::vector<ChannelFault>& faults,
                         const JsonWhere& w) {
    for (size_t k = 0; k < faults.size(); ++k) {
      if (faults[k].kind != ChannelFaultKind::kSwap) continue;
      const std::string& other = faults[k].with;
      if (other == name || (m.input_index(other) < 0 && m.output_index(other) < 0))
        json_fail(w / k / "with", "no other channel named \"" + other + "\"");
      const int oi = m.input_index(other), oo = m.output_index(other);
      const auto& theirs = oi >= 0 ? m.inputs[oi].faults : m.outputs[oo].faults;
      for (const ChannelFault& f : theirs) {
        if (f.kind == ChannelFaultKind::kSwap && f.with == name && name < other)
          json_fail(w / k, "the swap of " + name + " and " + other + " is listed on both");
      }
    }
  };
  for (size_t i = 0; i < m.inputs.size(); ++i)
    check_swaps(m.inputs[i].name, m.inputs[i].faults, root / "inputs" / i / "faults");
  for (size_t i = 0; i < m.outputs.size(); ++i)
    check_swaps(m.outputs[i].name, m.outputs[i].faults, root / "outputs" / i / "faults");
}

Model parse_model(const Json& doc, const std::string& source) {
  JsonWhere root{source, ""};
  json_require_object(doc, root);
  if (doc.contains("format") && doc["format"] == kStateSpaceFormat)
    return parse_state_space_model(doc, source);
  Model m;
  m.source = source;
  auto* warn = &m.warnings;
  m.extra = json_unknown_members(
      doc, root, {"format", "name", "operating_point", "inputs", "outputs", "paths"}, warn);
  const std::string format = json_string_member(doc, root, "format");
  if (format != kModelFormat) {
    json_fail(root / "format",
              "expected \"" + std::string(kModelFormat) + "\", found \"" + format + "\"");
  }
  if (doc.contains("name")) m.name = json_string_member(doc, root, "name");
  parse_operating_point(doc, root, m);
  std::set<std::string> names;
  const Json& ins = json_array_member(doc, root, "inputs");
  if (ins.empty()) json_fail(root / "inputs", "a model needs at least one input");
  for (size_t i = 0; i < ins.size(); ++i)
    m.inputs.push_back(model_input_from_json(ins[i], root / "inputs" / i, names, warn));
  const Json& outs = json_array_member(doc, root, "outputs");
  for (size_t i = 0; i < outs.size(); ++i)
    m.outputs.push_back(model_output_from_json(outs[i], root / "outputs" / i, names, warn));
  const Json& paths = json_array_member(doc, root, "paths", true);
  for (size_t i = 0; i < paths.size(); ++i)
    m.paths.push_back(model_path_from_json(paths[i], root / "paths" / i, m, warn));
  check_cross_references(m, root);
  return m;
}

Model load_model(const std::string& file) { return parse_model(json_load_file(file), file); }

Json model_to_json(const Model& m) {
  Json j = m.extra.is_object() ? m.extra : Json::object();
  j["format"] = kModelFormat;
  j["name"] = m.name;
  Json op = m.operating_point_extra.is_object() ? m.operating_point_extra : Json::object();
  op["speed_pct"] = m.speed_pct;
  op["steady_state"] = Json::object();
  for (const auto& [k, v] : m.steady_state) op["steady_state"][k] = v;
  j["operating_point"] = op;
  j["inputs"] = Json::array();
  for (const ModelInput& in : m.inputs) {
    Json ji = in.extra.is_object() ? in.extra : Json::object();
    ji["name"] = in.name;
    ji["units"] = in.units;
    ji["full_scale"] = in.full_scale;
    if (in.noise_rms > 0.0) ji["noise_rms"] = in.noise_rms;
    if (in.test_amplitude_pct > 0.0) ji["test_amplitude_pct"] = in.test_amplitude_pct;
    if (in.actuator || !in.nonlinearity.empty()) {
      Json a = Json::object();
      if (in.actuator) a["tf"] = tf_to_json(*in.actuator);
      if (!in.nonlinearity.empty()) {
        a["nonlinearity"] = Json::array();
        for (const auto& nl : in.nonlinearity) {
          Json jn{{"type", to_string(nl.kind)}};
          if (has_width(nl.kind)) jn["width"] = nl.width;
          if (nl.kind == NonlinearityKind::kRateLimit) jn["rate"] = nl.rate;
          if (nl.kind == NonlinearityKind::kSaturation) {
            jn["min"] = nl.min;
            jn["max"] = nl.max;
          }
          a["nonlinearity"].push_back(jn);
        }
      }
      ji["actuator"] = a;
    }
    if (!in.measurement_coupling.empty()) {
      ji["measurement_coupling"] = Json::array();
      for (const auto& c : in.measurement_coupling) {
        ji["measurement_coupling"].push_back({{"output", c.output}, {"gain", c.gain}});
      }
    }
    if (!in.faults.empty()) ji["faults"] = channel_faults_to_json(in.faults);
    j["inputs"].push_back(ji);
  }
  j["outputs"] = Json::array();
  for (const ModelOutput& out : m.outputs) {
    Json jo = out.extra.is_object() ? out.extra : Json::object();
    jo["name"] = out.name;
    jo["units"] = out.units;
    jo["noise_rms"] = out.noise_rms;
    if (out.sensor) jo["sensor"] = Json{{"tf", tf_to_json(*out.sensor)}};
    if (!out.faults.empty()) jo["faults"] = channel_faults_to_json(out.faults);
    j["outputs"].push_back(jo);
  }
  j["paths"] = Json::array();
  for (const ModelPath& p : m.paths) {
    Json jp = p.extra.is_object() ? p.extra : Json::object();
    jp["output"] = p.output;
    jp["input"] = p.input;
    jp["tf"] = tf_to_json(p.tf);
    j["paths"].push_back(jp);
  }
  return j;
}

void save_model(const std::string& file, const Model& m) { json_save_file(file, model_to_json(m)); }

int Model::input_index(const std::string& n) const {
  for (size_t i = 0; i < inputs.size(); ++i) {
    if (inputs[i].name == n) return static_cast<int>(i);
  }
  return -1;
}

int Model::output_index(const std::string& n) const {
  for (size_t i = 0; i < outputs.size(); ++i) {
    if (outputs[i].name == n) return static_cast<int>(i);
  }
  return -1;
}

const ModelPath* Model::path(const std::string& o, const std::string& i) const {
  for (const ModelPath& p : paths) {
    if (p.output == o && p.input == i) return &p;
  }
  return nullptr;
}

ModelPath* Model::path(const std::string& o, const std::string& i) {
  for (ModelPath& p : paths) {
    if (p.output == o && p.input == i) return &p;
  }
  return nullptr;
}

double Model::dc(const std::string& ch) const {
  auto it = steady_state.find(ch);
  return it == steady_state.end() ? 0.0 : it->second;
}

Complex Model::actuator_response(int i, double w) const {
  const auto& a = inputs.at(i).actuator;
  return a ? a->at(w) : Complex(1.0, 0.0);
}

Complex Model::sensor_response(int o, double w) const {
  const auto& s = outputs.at(o).sensor;
  return s ? s->at(w) : Complex(1.0, 0.0);
}

Complex Model::path_response(int o, int i, double w) const {
  const ModelPath* p = path(outputs.at(o).name, inputs.at(i).name);
  return p ? p->tf.at(w) : Complex(0.0, 0.0);
}

Complex Model::position_to_output(int o, int i, double w) const {
  return sensor_response(o, w) * path_response(o, i, w);
}

std::optional<Tf> Model::command_chain(const std::string& input, const std::string& ch) const {
  const int i = input_index(input);
  if (i < 0) return std::nullopt;
  const Tf act = inputs[i].actuator ? *inputs[i].actuator : Tf{};
  if (ch == command_channel(input)) return Tf{};
  if (ch == input) return act;
  const int o = output_index(ch);
  if (o < 0) return std::nullopt;
  const ModelPath* p = path(ch, input);
  if (!p) return std::nullopt;
  Tf t = act * p->tf;
  if (outputs[o].sensor) t = t * *outputs[o].sensor;
  return t;
}

Complex Model::command_to_output(int o, int i, double w) const {
  return position_to_output(o, i, w) * actuator_response(i, w);
}

}  // namespace fralab

#include <filesystem>

#include "fralab/plant/embedded_models.h"
#include "fralab/plant/schedule.h"

namespace fralab {

Model load_model_or_embedded(const std::string& spec) {
  if (std::filesystem::exists(spec)) return load_model(spec);
  if (const auto at = parse_model_at(spec)) {
    InterpolationOptions o;
    o.schedule_by = at->schedule_by;
    return model_at(load_model_set(at->set, at->schedule_by), at->x, o);
  }
  std::string names;
  for (const EmbeddedModel& e : embedded_models()) {
    std::string n = e.name;
    if (spec == n || spec + ".json" == n) {
      return parse_model(Json::parse(e.json), "embedded:" + n);
    }
    names += (names.empty() ? "" : ", ") + n.substr(0, n.size() - 5);
  }
  throw InputError(
      spec + ": no such model file, and no embedded model of that name (embedded: " + names + ")");
}

}  // namespace fralab
