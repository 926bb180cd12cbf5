// AcquireOptions at the edges (acquire/acquire_flags.h): every field, one at a time, goes through
// the argv a child process is given (acquire_flags, parsed by add_acquire_flags) and through the
// JSON form and comes back equal; the table has a row for every member of the struct; the argv's
// order is the one run.json has always recorded; bad JSON is refused by key.
#include "fralab/acquire/acquire_flags.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>
#include <map>
#include <set>
#include <utility>

namespace fralab {

// Printed by gtest when two options differ.
void PrintTo(const AcquireOptions& o, std::ostream* os) { *os << acquire_options_to_json(o); }

namespace {

using ::testing::ElementsAre;
using ::testing::ElementsAreArray;
using ::testing::HasSubstr;

// The number of members of an aggregate: the most initialisers T{...} takes. AnyMember converts
// to any member's type, so T{AnyMember, ...} with k initialisers compiles for every k up to the
// member count and not beyond (a member that is itself an aggregate, AdaptiveSineOptions, takes
// one initialiser: it converts directly, so no brace elision spreads it over its own members).
// The compiler counts, so nothing is maintained by hand beside the struct.
struct AnyMember {
  template <class T>
  operator T() const;  // only named in unevaluated contexts
};
template <class T, size_t... I>
constexpr bool takes_initialisers(std::index_sequence<I...>) {
  return requires { T{(void(I), AnyMember{})...}; };
}
template <class T, size_t N = 0>
constexpr size_t member_count() {
  if constexpr (!takes_initialisers<T>(std::make_index_sequence<N + 1>()))
    return N;
  else
    return member_count<T, N + 1>();
}

// Per flag, a value other than the default (and the group that writes it switched on: --lead is
// only written for a free-running plant). Doubles chosen so that 6 decimals would round them.
const std::map<std::string, std::function<void(AcquireOptions&)>>& changes() {
  static const std::map<std::string, std::function<void(AcquireOptions&)>> c = {
      {"--input", [](AcquireOptions& o) { o.inputs = "Wf,A8"; }},
      {"--band", [](AcquireOptions& o) { o.band = "0.5:20"; }},
      {"--excitation", [](AcquireOptions& o) { o.excitation = Excitation::kSweep; }},
      {"--multisine-phases", [](AcquireOptions& o) { o.multisine_phases = "schroeder"; }},
      {"--odd-lines", [](AcquireOptions& o) { o.odd_lines = true; }},
      {"--multisine-design",
       [](AcquireOptions& o) { o.multisine_design = MultisineOptions::Design::kZippered; }},
      {"--realisations", [](AcquireOptions& o) { o.realisations = 3; }},
      {"--points-per-decade", [](AcquireOptions& o) { o.points_per_decade = 7; }},
      {"--amplitude-pct", [](AcquireOptions& o) { o.amplitude_pct = 2.0 / 3.0; }},
      {"--amplitude-scale", [](AcquireOptions& o) { o.amplitude_scale = 1.0 / 3.0; }},
      {"--min-cycles", [](AcquireOptions& o) { o.min_cycles = 5; }},
      {"--min-integrate-s", [](AcquireOptions& o) { o.min_integrate_s = 0.1 + 0.2; }},
      {"--settle-cycles", [](AcquireOptions& o) { o.settle_cycles = 1e-7; }},
      {"--sample-rate", [](AcquireOptions& o) { o.sample_rate_hz = 2000.0 / 3.0; }},
      {"--speed", [](AcquireOptions& o) { o.speed = 12.345678901; }},
      {"--block", [](AcquireOptions& o) { o.block = 250; }},
      {"--window", [](AcquireOptions& o) { o.window = 5; }},
      {"--settle-time-constant-s", [](AcquireOptions& o) { o.slowest_time_constant_s = 0.7; }},
      {"--free-running", [](AcquireOptions& o) { o.free_running = true; }},
      {"--lead",
       [](AcquireOptions& o) {
         o.free_running = true;
         o.lead = 4;
       }},
      {"--max-repeats",
       [](AcquireOptions& o) {
         o.free_running = true;
         o.max_repeats = 1;
       }},
      {"--sigma-target", [](AcquireOptions& o) { o.adaptive.sigma_target = 0.01; }},
      {"--pilot-cycles",
       [](AcquireOptions& o) {
         o.adaptive.sigma_target = 0.02;
         o.adaptive.pilot_cycles = 6;
       }},
      {"--adaptive-decided",
       [](AcquireOptions& o) {
         o.adaptive.sigma_target = 0.02;
         o.adaptive_decided = "3*4,7*8";
       }},
      {"--zoom",
       [](AcquireOptions& o) {
         o.zoom = {{31.4, 0.02}, {200.0 / 3.0, 1.0 / 300}};
       }},
      {"--zoom-period-factor",
       [](AcquireOptions& o) {
         o.zoom = {{10, 0.05}};
         o.zoom_period_factor = 2.0 / 3.0 + 2;
       }},
  };
  return c;
}

// The options add_acquire_flags makes of `argv` (with `auto_campaign` as fralab measure binds it).
AcquireOptions parsed(const std::vector<std::string>& argv, bool* auto_campaign = nullptr) {
  CLI::App app;
  AcquireOptions back;
  add_acquire_flags(&app, back, auto_campaign);
  std::vector<std::string> args(argv.rbegin(), argv.rend());  // CLI11 parses a vector from its back
  app.parse(args);
  return back;
}

TEST(AcquireFlags, TheTableHasARowForEveryMemberOfTheOptions) {
  static_assert(member_count<AdaptiveSineOptions>() == 2, "the counter counts members");
  // AcquireOptions's members, its `adaptive` counted as AdaptiveSineOptions's own members.
  const size_t fields = member_count<AcquireOptions>() - 1 + member_count<AdaptiveSineOptions>();
  EXPECT_EQ(acquire_fields().size(), fields)
      << "a field of AcquireOptions (or AdaptiveSineOptions) is not a row of acquire_fields() "
         "(acquire/src/acquire_flags.cc)";
  std::set<std::string> flags, keys;
  for (const AcquireField& f : acquire_fields()) {
    EXPECT_TRUE(flags.insert(f.flag).second) << f.flag << " twice";
    EXPECT_TRUE(keys.insert(f.key).second) << f.key << " twice";
  }
}

TEST(AcquireFlags, EveryRowHasAChangeThatChangesItsOwnField) {
  std::set<std::string> rows, changed;
  for (const AcquireField& f : acquire_fields()) rows.insert(f.flag);
  for (const auto& [flag, change] : changes()) changed.insert(flag);
  EXPECT_EQ(rows, changed) << "each row of acquire_fields() needs its change in this test";
  for (const AcquireField& f : acquire_fields()) {
    if (!changes().count(f.flag)) continue;
    AcquireOptions o;
    changes().at(f.flag)(o);
    EXPECT_NE(f.to_json(o), f.to_json(AcquireOptions{})) << f.flag;
  }
}

TEST(AcquireFlags, EveryFieldComesBackThroughTheFlagsExactly) {
  for (const auto& [flag, change] : changes()) {
    AcquireOptions o;
    change(o);
    ASSERT_NE(o, AcquireOptions{}) << flag;
    EXPECT_EQ(parsed(acquire_flags(o)), o) << flag;
    bool auto_campaign = true;  // as fralab measure binds them: the words are never "auto"
    EXPECT_EQ(parsed(acquire_flags(o), &auto_campaign), o) << flag;
    EXPECT_FALSE(auto_campaign) << flag;
  }
  AcquireOptions all;  // every change at once
  for (const auto& [flag, change] : changes()) change(all);
  EXPECT_EQ(parsed(acquire_flags(all)), all);
}

TEST(AcquireFlags, EveryFieldComesBackThroughJsonExactly) {
  for (const auto& [flag, change] : changes()) {
    AcquireOptions o;
    change(o);
    const Json j = acquire_options_to_json(o);
    EXPECT_EQ(acquire_options_from_json(j, {"mem", ""}), o) << flag;
    // Through the text too: nlohmann writes the shortest number that reads back exactly.
    EXPECT_EQ(acquire_options_from_json(json_parse_text(j.dump(2), "text"), {"text", ""}), o)
        << flag;
  }
  AcquireOptions all;
  for (const auto& [flag, change] : changes()) change(all);
  EXPECT_EQ(acquire_options_from_json(json_parse_text(acquire_options_to_json(all).dump(), "t"),
                                      {"t", ""}),
            all);
  EXPECT_EQ(acquire_options_from_json(Json::object(), {"t", ""}), AcquireOptions{})
      << "a key left out keeps its default";
}

TEST(AcquireFlags, FlagsReproduceTheOptionsExactly) {
  AcquireOptions o;
  o.inputs = "Wf";
  o.band = "1:10";
  o.points_per_decade = 2;
  o.excitation = Excitation::kMultisine;
  o.amplitude_scale = 1.0 / 3.0;  // not representable in 6 decimals
  o.min_integrate_s = 0.1 + 0.2;
  o.odd_lines = true;
  o.slowest_time_constant_s = 0.7;
  const AcquireOptions back = parsed(acquire_flags(o));
  EXPECT_EQ(back.inputs, o.inputs);
  EXPECT_EQ(back.band, o.band);
  EXPECT_EQ(back.excitation, Excitation::kMultisine);
  EXPECT_EQ(back.amplitude_scale, o.amplitude_scale);  // bit for bit
  EXPECT_EQ(back.min_integrate_s, o.min_integrate_s);
  EXPECT_EQ(back.slowest_time_constant_s, 0.7);
  EXPECT_TRUE(back.odd_lines);
  EXPECT_EQ(back.window, o.window);
}

// run.json's options.acquire_flags holds these words; resume parses them in any order, but the
// record of a run is the same text as before.
TEST(AcquireFlags, TheArgvKeepsItsOrder) {
  EXPECT_THAT(acquire_flags(AcquireOptions{}),
              ElementsAreArray<std::string>({"--band",
                                             "0.04:100",
                                             "--excitation",
                                             "stepped",
                                             "--multisine-phases",
                                             "low-crest",
                                             "--multisine-design",
                                             "orthogonal",
                                             "--realisations",
                                             "1",
                                             "--points-per-decade",
                                             "10",
                                             "--amplitude-pct",
                                             "-1",
                                             "--amplitude-scale",
                                             "1",
                                             "--min-cycles",
                                             "8",
                                             "--min-integrate-s",
                                             "4",
                                             "--settle-cycles",
                                             "1",
                                             "--sample-rate",
                                             "1000",
                                             "--speed",
                                             "0",
                                             "--block",
                                             "0",
                                             "--window",
                                             "2",
                                             "--settle-time-constant-s",
                                             "-1"}));
  AcquireOptions all;
  for (const auto& [flag, change] : changes()) change(all);
  const std::vector<std::string> argv = acquire_flags(all);
  ASSERT_GE(argv.size(), 32u);
  EXPECT_THAT(
      std::vector<std::string>(argv.begin() + 32, argv.end()),
      ElementsAre("--odd-lines", "--free-running", "--lead", "4", "--max-repeats", "1", "--input",
                  "Wf,A8", "--sigma-target", "0.01", "--pilot-cycles", "6", "--adaptive-decided",
                  "3*4,7*8", "--zoom", "10:0.05", "--zoom-period-factor", lossless(2.0 / 3.0 + 2)));
  // A group that is off leaves its fields out: they do nothing then.
  AcquireOptions lockstep;
  lockstep.lead = 4;
  lockstep.adaptive.pilot_cycles = 6;
  EXPECT_EQ(acquire_flags(lockstep), acquire_flags(AcquireOptions{}));
}

TEST(AcquireFlags, AutoIsAnExcitationOfTheLabOnly) {
  bool auto_campaign = false;
  const AcquireOptions o = parsed({"--excitation", "auto"}, &auto_campaign);
  EXPECT_TRUE(auto_campaign);
  EXPECT_EQ(o.excitation, Excitation::kMultisine);
  EXPECT_THROW(parsed({"--excitation", "auto"}), CLI::ValidationError);
}

TEST(AcquireFlags, AZoomThatIsNotWnColonZetaIsRefusedNamingTheItem) {
  EXPECT_EQ(parsed({"--zoom", "31.4:0.02,62.8:0.01"}).zoom,
            (std::vector<ZoomMode>{{31.4, 0.02}, {62.8, 0.01}}));
  for (const char* bad : {"31.4", "31.4:", "31.4:0.02x", "wn:0.02", "31.4;0.02"}) {
    try {
      parsed({"--zoom", bad});
      ADD_FAILURE() << bad << " accepted";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(std::string("--zoom \"") + bad + "\"")) << bad;
    }
  }
}

TEST(AcquireFlags, TheJsonFormHasEveryKey) {
  EXPECT_EQ(acquire_options_to_json(AcquireOptions{}).dump(),
            R"({"adaptive":{"pilot_cycles":4,"sigma_target":0.0},"adaptive_decided":"",)"
            R"("amplitude_pct":-1.0,"amplitude_scale":1.0,"band":"0.04:100","block":0,)"
            R"("excitation":"stepped","free_running":false,"inputs":"","lead":10,)"
            R"("max_repeats":3,"min_cycles":8,"min_integrate_s":4.0,)"
            R"("multisine_design":"orthogonal","multisine_phases":"low-crest",)"
            R"("odd_lines":false,"points_per_decade":10,"realisations":1,)"
            R"("sample_rate_hz":1000.0,"settle_cycles":1.0,"slowest_time_constant_s":-1.0,)"
            R"("speed":0.0,"window":2,"zoom":[],"zoom_period_factor":1.0})");
}

TEST(AcquireFlags, BadJsonIsRefusedNamingTheKey) {
  auto error = [](const char* text) -> std::string {
    try {
      acquire_options_from_json(json_parse_text(text, "opts.json"), {"opts.json", "/acquire"});
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_THAT(error(R"({"block": "100"})"), HasSubstr("opts.json: /acquire/block: expected an"));
  EXPECT_THAT(error(R"({"block": 1.5})"), HasSubstr("/acquire/block: expected an integer"));
  EXPECT_THAT(error(R"({"speed": "fast"})"), HasSubstr("/acquire/speed: expected a number"));
  EXPECT_THAT(error(R"({"odd_lines": 1})"), HasSubstr("/acquire/odd_lines: expected true or"));
  EXPECT_THAT(error(R"({"excitation": "auto"})"),
              HasSubstr("/acquire/excitation: \"auto\": not one of stepped, sweep, multisine"));
  EXPECT_THAT(error(R"({"blocks": 100})"), HasSubstr("/acquire/blocks: unknown key"));
  EXPECT_THAT(error(R"({"adaptive": {"sigma": 0.1}})"),
              HasSubstr("/acquire/adaptive/sigma: unknown key"));
  EXPECT_THAT(error(R"({"adaptive": 0.1})"),
              HasSubstr("/acquire/adaptive: expected a JSON object"));
  EXPECT_THAT(error(R"([1])"), HasSubstr("opts.json: /acquire: expected a JSON object"));
  EXPECT_THAT(error(R"({"zoom": 3})"), HasSubstr("/acquire/zoom: expected an array"));
  EXPECT_THAT(error(R"({"zoom": [{"wn_rad_s": 3}]})"), HasSubstr("/acquire/zoom/0"));
  EXPECT_THAT(error(R"({"zoom": [{"wn_rad_s": 3}]})"), HasSubstr("zeta"));
}

}  // namespace
}  // namespace fralab
