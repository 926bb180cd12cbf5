#include "fralab/lab/run_record.h"

#include <limits>
#include <utility>

#include "fralab/core/text.h"

namespace fralab {

namespace {

constexpr std::pair<RunRecordState, const char*> kRunRecordStates[] = {
    {RunRecordState::kRunning, "running"},
    {RunRecordState::kComplete, "complete"},
    {RunRecordState::kPartial, "partial"},
    {RunRecordState::kFailed, "failed"},
    {RunRecordState::kInterrupted, "interrupted"}};

// The members of one object of a record, each error naming the file and the member's path.
class RecordReader {
 public:
  RecordReader(const Json& obj, JsonWhere where) : obj_(obj), where_(std::move(where)) {
    json_require_object(obj_, where_);
  }
  bool has(const std::string& key) const { return obj_.contains(key); }
  JsonWhere at(const std::string& key) const { return where_ / key; }
  const Json& member(const std::string& key) const { return json_member(obj_, where_, key); }
  RecordReader object(const std::string& key) const { return {member(key), at(key)}; }

  std::string string(const std::string& key) const { return json_string_member(obj_, where_, key); }
  bool boolean(const std::string& key) const { return json_bool(member(key), at(key)); }
  double number(const std::string& key) const { return json_number_member(obj_, where_, key); }
  int64_t integer(const std::string& key) const { return json_integer(member(key), at(key)); }
  int count(const std::string& key) const {  // an int >= 0
    const int64_t n = integer(key);
    if (n < 0 || n > std::numeric_limits<int>::max())
      json_fail(at(key), "expected a count (an integer >= 0), found " + member(key).dump());
    return int(n);
  }
  uint64_t unsigned_integer(const std::string& key) const {
    const Json& v = member(key);
    if (!v.is_number_unsigned()) json_fail(at(key), "expected an integer >= 0, found " + v.dump());
    return v.get<uint64_t>();
  }
  std::vector<std::string> strings(const std::string& key) const {
    const Json& a = json_array_member(obj_, where_, key);
    std::vector<std::string> v;
    for (size_t i = 0; i < a.size(); ++i) v.push_back(json_string(a[i], at(key) / i));
    return v;
  }
  std::map<std::string, std::string> string_map(const std::string& key) const {
    const RecordReader m = object(key);
    std::map<std::string, std::string> v;
    for (auto it = m.obj_.begin(); it != m.obj_.end(); ++it) v[it.key()] = m.string(it.key());
    return v;
  }
  std::optional<MeasurementChain> chain(const std::string& key) const {
    if (!has(key)) return std::nullopt;
    return chain_from_json(member(key), at(key));
  }
  // An optional member read by `read` (one of the readers above).
  template <class Read>
  auto optional(const std::string& key, Read read) const
      -> std::optional<decltype((this->*read)(key))> {
    if (!has(key)) return std::nullopt;
    return (this->*read)(key);
  }
  const Json& json() const { return obj_; }

 private:
  const Json& obj_;
  JsonWhere where_;
};

void write_run_outcome(const RunOutcome& o, Json& j) {
  j["state"] = to_string(o.state);
  if (o.reason) j["reason"] = *o.reason;
  if (o.failed_step)
    j["failed_step"] = {{"step", o.failed_step->step}, {"error", o.failed_step->error}};
  if (o.resumed) j["resumed"] = *o.resumed;
}

void read_run_outcome(const RecordReader& in, RunOutcome& o) {
  const std::string state = in.string("state");
  const std::optional<RunRecordState> s = enum_from_word(kRunRecordStates, state);
  if (!s)
    json_fail(in.at("state"),
              "\"" + state + "\": running, complete, partial, failed or interrupted");
  o.state = *s;
  o.reason = in.optional("reason", &RecordReader::string);
  if (in.has("failed_step")) {
    const RecordReader f = in.object("failed_step");
    o.failed_step = FailedStep{f.string("step"), f.string("error")};
  }
  o.resumed = in.optional("resumed", &RecordReader::count);
}

// The members of `read` that `typed` (the record as this version writes it) lacks, at any depth
// of the objects both hold, into `out` by JSON pointer.
void collect_unknown_members(const Json& read, const Json& typed, const Json::json_pointer& at,
                             Json& out) {
  for (auto it = read.begin(); it != read.end(); ++it) {
    const Json::json_pointer p = at / it.key();
    const auto t = typed.find(it.key());
    if (t == typed.end())
      out[p.to_string()] = it.value();
    else if (it->is_object() && t->is_object())
      collect_unknown_members(*it, *t, p, out);
  }
}

// Puts the unknown members back into `j`, each where its object still is.
void put_back_unknown_members(Json& j, const Json& unknown) {
  for (auto it = unknown.begin(); it != unknown.end(); ++it) {
    const Json::json_pointer p(it.key());
    const Json::json_pointer parent = p.parent_pointer();
    if (j.contains(parent) && j.at(parent).is_object() && !j.contains(p)) j[p] = it.value();
  }
}

}  // namespace

const char* to_string(RunRecordState s) { return enum_word(kRunRecordStates, s); }

Json run_record_to_json(const RunRecord& r) {
  Json j = Json::object();
  j["format"] = RunRecord::kFormat;
  j["run_id"] = r.run_id;
  j["engine"] = r.engine;
  j["inputs"] = r.inputs;
  j["pairs"] = r.pairs;
  const RunOptions& o = r.options;
  Json opt = {{"seed", o.seed},
              {"no_noise", o.no_noise},
              {"fit_delay", o.fit_delay},
              {"acquire_flags", o.acquire_flags}};
  if (o.fit) opt["fit"] = *o.fit;
  if (o.timeout_s) opt["timeout_s"] = *o.timeout_s;
  if (o.stall_timeout_s) opt["stall_timeout_s"] = *o.stall_timeout_s;
  if (o.hosts) opt["hosts"] = *o.hosts;
  if (o.deputy_url) opt["deputy_url"] = *o.deputy_url;
  j["options"] = std::move(opt);
  if (r.measurement_chain) j["measurement_chain"] = chain_to_json(*r.measurement_chain);
  j["lcm_url"] = r.lcm_url;
  write_run_outcome(r, j);
  if (r.engine_time_s) j["engine_time_s"] = *r.engine_time_s;
  if (r.wall_time_s) j["wall_time_s"] = *r.wall_time_s;
  if (r.speedup) j["speedup"] = *r.speedup;
  if (r.tape_blocks) j["tape_blocks"] = *r.tape_blocks;
  if (r.fit_time_s) j["fit_time_s"] = *r.fit_time_s;
  if (r.retransmissions) j["retransmissions"] = *r.retransmissions;
  if (r.items_retransmitted) j["items_retransmitted"] = *r.items_retransmitted;
  if (r.adaptive) j["adaptive"] = *r.adaptive;
  if (r.data_quality) j["data_quality"] = data_quality_to_json(*r.data_quality);
  if (!r.zoom.empty()) {
    Json& z = j["zoom"] = Json::array();
    for (const ZoomPlacement& p : r.zoom)
      z.push_back({{"wn_rad_s", p.mode.wn_rad_s},
                   {"zeta", p.mode.zeta},
                   {"lines_in_band", p.lines_in_band},
                   {"lines_in_reach", p.lines_in_reach},
                   {"resolution_hz", p.resolution_hz},
                   {"zoomed", p.zoomed},
                   {"period_needed_s", p.period_needed_s}});
  }
  put_back_unknown_members(j, r.unknown);
  return j;
}

RunRecord run_record_from_json(const Json& j, const std::string& file) {
  const RecordReader in(j, {file, ""});
  RunRecord r;
  if (const std::string f = in.string("format"); f != RunRecord::kFormat)
    json_fail(in.at("format"), "\"" + f + "\": expected " + RunRecord::kFormat);
  r.run_id = in.string("run_id");
  r.engine = in.string("engine");
  r.inputs = in.string("inputs");
  r.pairs = in.strings("pairs");
  const RecordReader opt = in.object("options");
  r.options.seed = opt.unsigned_integer("seed");
  r.options.no_noise = opt.boolean("no_noise");
  r.options.fit_delay = opt.string("fit_delay");
  r.options.fit = opt.optional("fit", &RecordReader::boolean);
  r.options.timeout_s = opt.optional("timeout_s", &RecordReader::number);
  r.options.stall_timeout_s = opt.optional("stall_timeout_s", &RecordReader::number);
  r.options.hosts = opt.optional("hosts", &RecordReader::string_map);
  r.options.deputy_url = opt.optional("deputy_url", &RecordReader::string);
  r.options.acquire_flags = opt.strings("acquire_flags");
  r.measurement_chain = in.chain("measurement_chain");
  r.lcm_url = in.string("lcm_url");
  read_run_outcome(in, r);
  r.engine_time_s = in.optional("engine_time_s", &RecordReader::number);
  r.wall_time_s = in.optional("wall_time_s", &RecordReader::number);
  r.speedup = in.optional("speedup", &RecordReader::number);
  r.tape_blocks = in.optional("tape_blocks", &RecordReader::integer);
  r.fit_time_s = in.optional("fit_time_s", &RecordReader::number);
  r.retransmissions = in.optional("retransmissions", &RecordReader::integer);
  r.items_retransmitted = in.optional("items_retransmitted", &RecordReader::integer);
  if (in.has("adaptive")) {
    json_require_object(in.member("adaptive"), in.at("adaptive"));
    r.adaptive = in.member("adaptive");
  }
  if (in.has("data_quality"))
    r.data_quality = data_quality_from_json(in.member("data_quality"), in.at("data_quality"));
  if (in.has("zoom")) {
    const Json& a = json_array_member(j, {file, ""}, "zoom");
    for (size_t i = 0; i < a.size(); ++i) {
      const RecordReader z(a[i], in.at("zoom") / i);
      ZoomPlacement p;
      p.mode = {z.number("wn_rad_s"), z.number("zeta")};
      p.lines_in_band = z.count("lines_in_band");
      p.lines_in_reach = z.count("lines_in_reach");
      p.resolution_hz = z.number("resolution_hz");
      p.zoomed = z.boolean("zoomed");
      p.period_needed_s = z.number("period_needed_s");
      r.zoom.push_back(p);
    }
  }
  collect_unknown_members(j, run_record_to_json(r), Json::json_pointer(), r.unknown);
  return r;
}

Json auto_run_record_to_json(const AutoRunRecord& r) {
  Json j = Json::object();
  write_run_outcome(r, j);
  j["excitation"] = "auto";
  if (r.fit_delay) j["fit_delay"] = *r.fit_delay;
  j["engine"] = r.engine;
  j["seed"] = r.seed;
  j["engine_time_s"] = r.engine_time_s;
  j["wall_time_s"] = r.wall_time_s;
  j["speedup"] = r.speedup;
  j["multisine"] = {{"dir", r.multisine.dir}, {"engine_time_s", r.multisine.engine_time_s}};
  j["sine"] = {
      {"dir", r.sine.dir}, {"engine_time_s", r.sine.engine_time_s}, {"inputs", r.sine.inputs}};
  Json inputs = Json::object();
  for (const auto& [x, in] : r.inputs)
    inputs[x] = {{"nl_rel_median", in.nl_rel_median}, {"measured_by", in.measured_by}};
  j["inputs"] = std::move(inputs);
  j["nl_threshold"] = r.nl_threshold;
  if (r.measurement_chain) j["measurement_chain"] = chain_to_json(*r.measurement_chain);
  j["pairs"] = r.pairs;
  put_back_unknown_members(j, r.unknown);
  return j;
}

AutoRunRecord auto_run_record_from_json(const Json& j, const std::string& file) {
  const RecordReader in(j, {file, ""});
  AutoRunRecord r;
  if (const std::string e = in.string("excitation"); e != "auto")
    json_fail(in.at("excitation"), "\"" + e + "\": expected auto (an auto campaign's record)");
  read_run_outcome(in, r);
  r.fit_delay = in.optional("fit_delay", &RecordReader::string);
  r.engine = in.string("engine");
  r.seed = in.unsigned_integer("seed");
  r.engine_time_s = in.number("engine_time_s");
  r.wall_time_s = in.number("wall_time_s");
  r.speedup = in.number("speedup");
  const RecordReader ms = in.object("multisine");
  r.multisine.dir = ms.string("dir");
  r.multisine.engine_time_s = ms.number("engine_time_s");
  const RecordReader sine = in.object("sine");
  r.sine.dir = sine.string("dir");
  r.sine.engine_time_s = sine.number("engine_time_s");
  r.sine.inputs = sine.strings("inputs");
  const RecordReader inputs = in.object("inputs");
  for (auto it = inputs.json().begin(); it != inputs.json().end(); ++it) {
    const RecordReader x = inputs.object(it.key());
    r.inputs[it.key()] = AutoRunInput{x.number("nl_rel_median"), x.string("measured_by")};
  }
  r.nl_threshold = in.number("nl_threshold");
  r.measurement_chain = in.chain("measurement_chain");
  r.pairs = in.strings("pairs");
  collect_unknown_members(j, auto_run_record_to_json(r), Json::json_pointer(), r.unknown);
  return r;
}

AnyRunRecord load_any_run_record(const std::string& file) {
  const Json j = json_load_file(file);
  if (j.is_object() && j.contains("excitation") && j["excitation"] == "auto")
    return auto_run_record_from_json(j, file);
  return run_record_from_json(j, file);
}

RunRecord load_run_record(const std::string& file) {
  AnyRunRecord r = load_any_run_record(file);
  if (!std::holds_alternative<RunRecord>(r))
    throw InputError(file + ": an auto campaign's record, not a fralab-run/1 run's");
  return std::get<RunRecord>(std::move(r));
}

AutoRunRecord load_auto_run_record(const std::string& file) {
  AnyRunRecord r = load_any_run_record(file);
  if (!std::holds_alternative<AutoRunRecord>(r))
    throw InputError(file + ": a fralab-run/1 run's record, not an auto campaign's");
  return std::get<AutoRunRecord>(std::move(r));
}

void save_run_record(const std::string& file, const RunRecord& r) {
  json_save_file(file, run_record_to_json(r));
}

void save_run_record(const std::string& file, const AutoRunRecord& r) {
  json_save_file(file, auto_run_record_to_json(r));
}

}  // namespace fralab
