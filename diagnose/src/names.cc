// The diagnosis' words at its edges (diagnose.h, parameter.h): causes, scopes and a finding's
// parameters, as diagnosis.json and the reports write them.
#include <utility>

#include "causes/cause.h"
#include "fralab/core/text.h"
#include "fralab/diagnose/diagnose.h"
#include "fralab/diagnose/parameter.h"

namespace fralab {

using diag::cause_unit;
using diag::cause_units;
using diag::CauseUnit;

namespace {

constexpr std::pair<Scope, const char*> kScopeNames[] = {{Scope::kPath, "path"},
                                                         {Scope::kOutput, "output"},
                                                         {Scope::kInput, "input"},
                                                         {Scope::kPlant, "plant"}};

constexpr std::pair<Param, const char*> kParamWords[] = {
    {Param::kCol, "col"},
    {Param::kCornerRadS, "corner_rad_s"},
    {Param::kDelayS, "delay_s"},
    {Param::kFrom, "from"},
    {Param::kFromRadS, "from_rad_s"},
    {Param::kFromZeta, "from_zeta"},
    {Param::kGain, "gain"},
    {Param::kGainDb, "gain_db"},
    {Param::kNotch, "notch"},
    {Param::kPoles, "poles"},
    {Param::kRow, "row"},
    {Param::kSign, "sign"},
    {Param::kTimeConstantFromS, "time_constant_from_s"},
    {Param::kTimeConstantToS, "time_constant_to_s"},
    {Param::kTo, "to"},
    {Param::kToRadS, "to_rad_s"},
    {Param::kToZeta, "to_zeta"},
    {Param::kWidth, "width"},
    {Param::kWnRadS, "wn_rad_s"},
    {Param::kZeros, "zeros"},
    {Param::kZeta, "zeta"},
};

}  // namespace

const char* to_string(CauseKind c) {
  const CauseUnit* unit = cause_unit(c);
  return unit ? unit->name() : "?";
}

const char* to_string(Scope s) { return enum_word(kScopeNames, s); }

std::string finding_label(const Finding& f) {
  std::string s = std::string(to_string(f.cause)) + " [" + to_string(f.scope);
  for (const std::string* n : {&f.input, &f.output})
    if (!n->empty()) s += " " + *n;
  return s + "]";
}

CauseKind cause_from_string(const std::string& s) {
  for (const CauseUnit* unit : cause_units())
    if (s == unit->name()) return unit->kind();
  throw InputError("unknown diagnosis cause '" + s + "'");
}

Scope scope_from_string(const std::string& s) {
  if (const auto k = enum_from_word(kScopeNames, s)) return *k;
  throw InputError("unknown diagnosis scope '" + s + "' (path, output, input or plant)");
}

const char* to_string(Param p) { return enum_word(kParamWords, p); }

std::optional<Param> param_from_string(const std::string& word) {
  return enum_from_word(kParamWords, word);
}

}  // namespace fralab
