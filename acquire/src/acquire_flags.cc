#include "fralab/acquire/acquire_flags.h"

#include <algorithm>
#include <limits>
#include <set>
#include <type_traits>

#include "fralab/core/text.h"

namespace fralab {

namespace {

using Written = AcquireField::Written;

// A field's value as the words after its flag: integers as std::to_string, doubles losslessly.
std::string flag_word(const std::string& v) { return v; }
std::string flag_word(int v) { return std::to_string(v); }
std::string flag_word(double v) { return lossless(v); }

// A field's value from JSON, of the field's type; InputError naming `where` otherwise.
template <class T>
T json_field_value(const Json& v, const JsonWhere& where) {
  if constexpr (std::is_same_v<T, bool>) {
    return json_bool(v, where);
  } else if constexpr (std::is_same_v<T, int>) {
    const int64_t n = json_integer(v, where);
    if (n < std::numeric_limits<int>::min() || n > std::numeric_limits<int>::max())
      json_fail(where, "expected an integer, found " + v.dump());
    return int(n);
  } else if constexpr (std::is_same_v<T, double>) {
    return json_number(v, where);
  } else {
    static_assert(std::is_same_v<T, std::string>);
    return json_string(v, where);
  }
}

// The field `get(o)` names (a generic lambda, so that one accessor serves the const options being
// written and the ones being set) as a JSON value of its own type.
template <class Get>
void set_json_accessors(AcquireField& f, Get get) {
  using T = std::remove_cvref_t<decltype(get(std::declval<AcquireOptions&>()))>;
  f.to_json = [get](const AcquireOptions& o) { return Json(get(o)); };
  f.from_json = [get](AcquireOptions& o, const Json& v, const JsonWhere& where) {
    get(o) = json_field_value<T>(v, where);
  };
}

// A field that takes a value: a string, an int or a double. `show_default`: --help shows the
// value the options had when the flag was added.
template <class Get>
AcquireField value_field(const char* flag, const char* key, const char* help, bool show_default,
                         Written written, Get get) {
  AcquireField f{flag, key, written, nullptr, nullptr, nullptr, nullptr};
  f.bind = [flag = std::string(flag), help = std::string(help), show_default, get](
               CLI::App* app, AcquireOptions& o, bool*) {
    CLI::Option* opt = app->add_option(flag, get(o), help);
    if (show_default) opt->capture_default_str();
  };
  f.words = [get](const AcquireOptions& o) { return std::vector<std::string>{flag_word(get(o))}; };
  set_json_accessors(f, get);
  return f;
}

// A switch (a bool set by the flag's presence): no words after it.
template <class Get>
AcquireField switch_field(const char* flag, const char* key, const char* help, Written written,
                          Get get) {
  AcquireField f{flag, key, written, nullptr, nullptr, nullptr, nullptr};
  f.bind = [flag = std::string(flag), help = std::string(help), get](
               CLI::App* app, AcquireOptions& o, bool*) { app->add_flag(flag, get(o), help); };
  f.words = [](const AcquireOptions&) { return std::vector<std::string>{}; };
  set_json_accessors(f, get);
  return f;
}

// An enumeration, on the command line and in JSON as one of `words` (to_word / from_word).
template <class Get, class ToWord, class FromWord>
AcquireField word_field(const char* flag, const char* key, const char* help,
                        std::vector<std::string> words, Get get, ToWord to_word,
                        FromWord from_word) {
  AcquireField f{flag, key, Written::kAlways, nullptr, nullptr, nullptr, nullptr};
  f.bind = [flag = std::string(flag), help = std::string(help), words, get, to_word, from_word](
               CLI::App* app, AcquireOptions& o, bool*) {
    app->add_option_function<std::string>(
           flag, [&o, get, from_word](const std::string& w) { get(o) = from_word(w); }, help)
        ->check(CLI::IsMember(words))
        ->default_str(to_word(get(o)));
  };
  f.words = [get, to_word](const AcquireOptions& o) {
    return std::vector<std::string>{to_word(get(o))};
  };
  f.to_json = [get, to_word](const AcquireOptions& o) { return Json(to_word(get(o))); };
  f.from_json = [get, words, from_word](AcquireOptions& o, const Json& v, const JsonWhere& where) {
    const std::string w = json_field_value<std::string>(v, where);
    if (std::find(words.begin(), words.end(), w) == words.end()) {
      std::string list;
      for (const std::string& k : words) list += (list.empty() ? "" : ", ") + k;
      json_fail(where, "\"" + w + "\": not one of " + list);
    }
    get(o) = from_word(w);
  };
  return f;
}

// --excitation: a word field, and with `auto_campaign` also "auto" (lab/auto_campaign.h), which
// is a multisine here.
AcquireField excitation_field() {
  auto get = [](auto& o) -> auto& { return o.excitation; };
  AcquireField f = word_field(
      "--excitation", "/excitation", "", {"stepped", "sweep", "multisine"}, get,
      [](Excitation e) { return std::string(to_string(e)); }, excitation_from_string);
  f.bind = [](CLI::App* c, AcquireOptions& o, bool* auto_campaign) {
    c->add_option_function<std::string>(
         "--excitation",
         [&o, auto_campaign](const std::string& word) {
           if (auto_campaign) *auto_campaign = word == "auto";
           o.excitation = excitation_from_string(word == "auto" ? "multisine" : word);
         },
         std::string("stepped (stepped sine), sweep (continuous log sweep) or multisine (all "
                     "inputs at once; --min-cycles = periods per experiment)") +
             (auto_campaign ? "; auto: multisine, then sine for the actuators that distort at its "
                              "level"
                            : ""))
        ->check(auto_campaign ? CLI::IsMember({"stepped", "sweep", "multisine", "auto"})
                              : CLI::IsMember({"stepped", "sweep", "multisine"}))
        ->default_str(auto_campaign && *auto_campaign ? "auto" : to_string(o.excitation));
  };
  return f;
}

// --zoom WN:ZETA[,WN:ZETA...] (rad/s and the damping ratio): in JSON an array of {"wn_rad_s",
// "zeta"}.
std::vector<ZoomMode> parse_zoom(const std::string& text) {
  std::vector<ZoomMode> modes;
  for (const std::string& item : split_list(text)) {
    const auto wn_zeta = number_pair(item);
    if (!wn_zeta)
      throw InputError("--zoom \"" + item + "\": expected WN_RAD_S:ZETA, e.g. 31.4:0.02");
    modes.push_back({wn_zeta->first, wn_zeta->second});
  }
  return modes;
}

AcquireField zoom_field() {
  AcquireField f{"--zoom", "/zoom", Written::kIfZoom, nullptr, nullptr, nullptr, nullptr};
  f.bind = [](CLI::App* app, AcquireOptions& o, bool*) {
    app->add_option_function<std::string>(
        "--zoom", [&o](const std::string& text) { o.zoom = parse_zoom(text); },
        "multisine: lightly damped modes WN_RAD_S:ZETA[,...] to resolve (lines around each, "
        "the period longer within --zoom-period-factor)");
  };
  f.words = [](const AcquireOptions& o) {
    std::string text;
    for (const ZoomMode& z : o.zoom)
      text += (text.empty() ? "" : ",") + lossless(z.wn_rad_s) + ":" + lossless(z.zeta);
    return std::vector<std::string>{text};
  };
  f.to_json = [](const AcquireOptions& o) {
    Json a = Json::array();
    for (const ZoomMode& z : o.zoom) a.push_back({{"wn_rad_s", z.wn_rad_s}, {"zeta", z.zeta}});
    return a;
  };
  f.from_json = [](AcquireOptions& o, const Json& v, const JsonWhere& where) {
    if (!v.is_array()) json_fail(where, "expected an array of {\"wn_rad_s\", \"zeta\"}");
    o.zoom.clear();
    for (size_t j = 0; j < v.size(); ++j) {
      const JsonWhere at = where / j;
      json_require_object(v[j], at);
      o.zoom.push_back(
          {json_number_member(v[j], at, "wn_rad_s"), json_number_member(v[j], at, "zeta")});
    }
  };
  return f;
}

// What is excited and how: the inputs, the band, the excitation and its design, the density.
std::vector<AcquireField> excitation_fields() {
  const bool kShow = true, kHide = false;
  return {
      value_field(
          "--input", "/inputs", "input(s) NAME[,NAME...] to excite (default: all)", kHide,
          Written::kIfInputs, [](auto& o) -> auto& { return o.inputs; }),
      value_field(
          "--band", "/band", "LO_HZ:HI_HZ", kShow, Written::kAlways,
          [](auto& o) -> auto& { return o.band; }),
      excitation_field(),
      value_field(
          "--multisine-phases", "/multisine_phases",
          "schroeder, random or low-crest (random, then envelope clipping)", kShow,
          Written::kAlways, [](auto& o) -> auto& { return o.multisine_phases; }),
      switch_field(
          "--odd-lines", "/odd_lines", "multisine: odd harmonics only", Written::kIfOddLines,
          [](auto& o) -> auto& { return o.odd_lines; }),
      word_field(
          "--multisine-design", "/multisine_design",
          "orthogonal (every input on every line, n_u experiments, DFT phase matrix) or zippered "
          "(disjoint lines, one experiment)",
          {"orthogonal", "zippered"}, [](auto& o) -> auto& { return o.multisine_design; },
          [](MultisineOptions::Design d) { return std::string(to_string(d)); },
          multisine_design_from_string),
      value_field(
          "--realisations", "/realisations",
          "orthogonal multisine: random-phase realisations (> 1: with --multisine-phases "
          "random; separates nonlinear distortion from noise)",
          kShow, Written::kAlways, [](auto& o) -> auto& { return o.realisations; }),
      value_field(
          "--points-per-decade", "/points_per_decade", "", kShow, Written::kAlways,
          [](auto& o) -> auto& { return o.points_per_decade; }),
  };
}

// How hard and how long: the amplitude, the cycles and settling, the sample rate, the speed and
// blocks.
std::vector<AcquireField> level_and_timing_fields() {
  const bool kShow = true, kHide = false;
  return {
      value_field(
          "--amplitude-pct", "/amplitude_pct",
          "% of full scale (default: the input's test_amplitude_pct, else 2)", kHide,
          Written::kAlways, [](auto& o) -> auto& { return o.amplitude_pct; }),
      value_field(
          "--amplitude-scale", "/amplitude_scale", "multiplies every input's amplitude", kShow,
          Written::kAlways, [](auto& o) -> auto& { return o.amplitude_scale; }),
      value_field(
          "--min-cycles", "/min_cycles", "", kShow, Written::kAlways,
          [](auto& o) -> auto& { return o.min_cycles; }),
      value_field(
          "--min-integrate-s", "/min_integrate_s", "", kShow, Written::kAlways,
          [](auto& o) -> auto& { return o.min_integrate_s; }),
      value_field(
          "--settle-cycles", "/settle_cycles",
          "stepped sine: cycles of settle per step, at least (and >= 5 time constants)", kShow,
          Written::kAlways, [](auto& o) -> auto& { return o.settle_cycles; }),
      value_field(
          "--sample-rate", "/sample_rate_hz", "Hz", kShow, Written::kAlways,
          [](auto& o) -> auto& { return o.sample_rate_hz; }),
      value_field(
          "--speed", "/speed", "1 = real time, 100 = 100x, 0 = as fast as consumers keep up", kShow,
          Written::kAlways, [](auto& o) -> auto& { return o.speed; }),
      value_field(
          "--block", "/block",
          "samples per command and tape block; 0: half a second of samples, at most what keeps "
          "a tape block under 60 kB",
          kShow, Written::kAlways, [](auto& o) -> auto& { return o.block; }),
      value_field(
          "--window", "/window", "blocks in flight ahead of the slowest consumer", kShow,
          Written::kAlways, [](auto& o) -> auto& { return o.window; }),
      value_field(
          "--settle-time-constant-s", "/slowest_time_constant_s",
          "settling time constant, s (default: the model's slowest)", kHide, Written::kAlways,
          [](auto& o) -> auto& { return o.slowest_time_constant_s; }),
  };
}

// The plant on its own clock, the adaptive stepped sine, and the multisine zoom.
std::vector<AcquireField> free_running_and_adaptive_fields() {
  const bool kShow = true, kHide = false;
  return {
      switch_field(
          "--free-running", "/free_running",
          "the plant runs on its own clock at --speed (not in lockstep); commands are "
          "kept --lead blocks ahead and a step an underrun touches is repeated",
          Written::kIfFreeRunning, [](auto& o) -> auto& { return o.free_running; }),
      value_field(
          "--lead", "/lead", "free-running: command blocks ahead of the plant's clock", kShow,
          Written::kIfFreeRunning, [](auto& o) -> auto& { return o.lead; }),
      value_field(
          "--max-repeats", "/max_repeats",
          "free-running: rounds of repeated steps before the run fails", kShow,
          Written::kIfFreeRunning, [](auto& o) -> auto& { return o.max_repeats; }),
      value_field(
          "--sigma-target", "/adaptive/sigma_target",
          "stepped sine, adaptive: integrate each step until sigma / |G| on every pair of "
          "its input is at most this (e.g. 0.01), at most the fixed plan's cycles "
          "(--min-cycles, --min-integrate-s); 0: the fixed plan",
          kShow, Written::kIfAdaptive, [](auto& o) -> auto& { return o.adaptive.sigma_target; }),
      value_field(
          "--pilot-cycles", "/adaptive/pilot_cycles",
          "adaptive: cycles of each step's first window, and the unit of its extensions", kShow,
          Written::kIfAdaptive, [](auto& o) -> auto& { return o.adaptive.pilot_cycles; }),
      value_field(
          "--adaptive-decided", "/adaptive_decided",
          "adaptive, resume: the extensions taken before, STEP*CYCLES,... (from the tape)", kHide,
          Written::kIfAdaptiveDecided, [](auto& o) -> auto& { return o.adaptive_decided; }),
      zoom_field(),
      value_field(
          "--zoom-period-factor", "/zoom_period_factor",
          "multisine zoom: the period may grow to this many times 1 / the band's low end for a "
          "zoomed mode's resolution (1: it does not)",
          kShow, Written::kIfZoom, [](auto& o) -> auto& { return o.zoom_period_factor; }),
  };
}

// Every flag, in the order of --help and acquire.json.
std::vector<AcquireField> make_acquire_fields() {
  std::vector<AcquireField> all;
  for (auto&& part :
       {excitation_fields(), level_and_timing_fields(), free_running_and_adaptive_fields()})
    all.insert(all.end(), part.begin(), part.end());
  return all;
}

}  // namespace

const std::vector<AcquireField>& acquire_fields() {
  static const std::vector<AcquireField> fields = make_acquire_fields();
  return fields;
}

bool written_for(Written w, const AcquireOptions& o) {
  switch (w) {
    case Written::kAlways:
      return true;
    case Written::kIfOddLines:
      return o.odd_lines;
    case Written::kIfFreeRunning:
      return o.free_running;
    case Written::kIfInputs:
      return !o.inputs.empty();
    case Written::kIfAdaptive:
      return o.adaptive.enabled();
    case Written::kIfAdaptiveDecided:
      return o.adaptive.enabled() && !o.adaptive_decided.empty();
    case Written::kIfZoom:
      return !o.zoom.empty();
  }
  return false;
}

void add_acquire_flags(CLI::App* c, AcquireOptions& o, bool* auto_campaign) {
  for (const AcquireField& f : acquire_fields()) f.bind(c, o, auto_campaign);
}

std::vector<std::string> acquire_flags(const AcquireOptions& o) {
  std::vector<std::string> argv;
  for (Written w :
       {Written::kAlways, Written::kIfOddLines, Written::kIfFreeRunning, Written::kIfInputs,
        Written::kIfAdaptive, Written::kIfAdaptiveDecided, Written::kIfZoom}) {
    if (!written_for(w, o)) continue;
    for (const AcquireField& f : acquire_fields()) {
      if (f.written != w) continue;
      argv.push_back(f.flag);
      for (std::string& word : f.words(o)) argv.push_back(std::move(word));
    }
  }
  return argv;
}

Json acquire_options_to_json(const AcquireOptions& o) {
  Json j = Json::object();
  for (const AcquireField& f : acquire_fields()) j[Json::json_pointer(f.key)] = f.to_json(o);
  return j;
}

namespace {

// Refuses a member of the object at `path` (a JSON pointer, "" the root) that is neither a field
// nor an object holding fields (the "adaptive" object).
void refuse_unknown_option_keys(const Json& obj, const std::string& path, const JsonWhere& where,
                                const std::set<std::string>& leaves,
                                const std::set<std::string>& parents) {
  const JsonWhere here{where.file, where.path + path};
  json_require_object(obj, here);
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    const std::string key = path + "/" + it.key();
    if (leaves.count(key)) continue;
    if (!parents.count(key))
      json_fail(here / it.key(), "unknown key: not an acquisition option (docs/formats.md §27)");
    refuse_unknown_option_keys(it.value(), key, where, leaves, parents);
  }
}

}  // namespace

AcquireOptions acquire_options_from_json(const Json& j, const JsonWhere& where) {
  json_require_object(j, where);
  AcquireOptions o;
  std::set<std::string> leaves, parents;
  for (const AcquireField& f : acquire_fields()) {
    leaves.insert(f.key);
    for (size_t slash = f.key.find('/', 1); slash != std::string::npos;
         slash = f.key.find('/', slash + 1))
      parents.insert(f.key.substr(0, slash));
  }
  refuse_unknown_option_keys(j, "", where, leaves, parents);
  for (const AcquireField& f : acquire_fields()) {
    const Json::json_pointer p(f.key);
    if (j.contains(p)) f.from_json(o, j.at(p), JsonWhere{where.file, where.path + f.key});
  }
  return o;
}

}  // namespace fralab
