#include "fralab/core/json_util.h"

#include <cmath>
#include <fstream>
#include <sstream>

namespace fralab {

void json_fail(const JsonWhere& where, const std::string& message) {
  throw InputError(where.str() + ": " + message);
}

namespace {

// Parses `in`, whose errors name `file` (a file, or where a text came from).
Json parse_limited(std::istream& in, const std::string& file) {
  // No fralab file nests deeper than a few levels: a depth limit keeps a hostile file (200,000
  // nested arrays) from exhausting the stack of whatever walks it.
  int64_t deepest_at = -1;
  auto limit = [&](int depth, Json::parse_event_t, Json&) {
    if (depth >= kMaxJsonDepth && deepest_at < 0) deepest_at = in.tellg();  // depth from 0
    return depth < kMaxJsonDepth;  // false: the value is dropped
  };
  Json j;
  try {
    j = Json::parse(in, limit, true, false);
  } catch (const Json::exception& e) {  // parse_error, a number overflowing (out_of_range), ...
    throw InputError(file + ": malformed JSON: " + e.what());
  } catch (const std::bad_alloc&) {
    throw InputError(file + ": too large to read into memory");
  }
  if (deepest_at >= 0)
    throw InputError(file + ": JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
                     " levels (near byte " + std::to_string(deepest_at) + "): not a fralab file");
  return j;
}

}  // namespace

Json json_load_file(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file + ": cannot open for reading (check the path)");
  return parse_limited(in, file);
}

Json json_parse_text(const std::string& text, const std::string& where) {
  std::istringstream in(text);
  return parse_limited(in, where);
}

void json_save_file(const std::string& file, const Json& j) {
  std::ofstream out(file);
  if (!out) throw InputError(file + ": cannot open for writing (does the folder exist?)");
  out << j.dump(2) << "\n";
  if (!out) throw InputError(file + ": write failed");
}

void json_require_object(const Json& obj, const JsonWhere& where) {
  if (!obj.is_object())
    json_fail(where, "expected a JSON object, found " + std::string(obj.type_name()));
}

const Json& json_member(const Json& obj, const JsonWhere& where, const std::string& key) {
  json_require_object(obj, where);
  auto it = obj.find(key);
  if (it == obj.end()) json_fail(where, "missing required key \"" + key + "\"");
  return *it;
}

double json_number(const Json& v, const JsonWhere& where) {
  if (!v.is_number()) {
    json_fail(where, "expected a number, found " + std::string(v.type_name()) + " " + v.dump());
  }
  double x = v.get<double>();
  if (!std::isfinite(x)) json_fail(where, "expected a finite number, found " + v.dump());
  return x;
}

bool json_bool(const Json& v, const JsonWhere& where) {
  if (!v.is_boolean()) json_fail(where, "expected true or false, found " + v.dump());
  return v.get<bool>();
}

int64_t json_integer(const Json& v, const JsonWhere& where) {
  if (!v.is_number_integer() || (v.is_number_unsigned() && v.get<uint64_t>() > uint64_t(INT64_MAX)))
    json_fail(where, "expected an integer, found " + v.dump());
  return v.get<int64_t>();
}

std::string json_string(const Json& v, const JsonWhere& where) {
  if (!v.is_string()) json_fail(where, "expected a string, found " + v.dump());
  return v.get<std::string>();
}

double json_number_member(const Json& obj, const JsonWhere& where, const std::string& key) {
  return json_number(json_member(obj, where, key), where / key);
}

double json_number_member(const Json& obj, const JsonWhere& where, const std::string& key,
                          double fallback) {
  json_require_object(obj, where);
  auto it = obj.find(key);
  if (it == obj.end()) return fallback;
  return json_number(*it, where / key);
}

std::string json_string_member(const Json& obj, const JsonWhere& where, const std::string& key) {
  return json_string(json_member(obj, where, key), where / key);
}

const Json& json_array_member(const Json& obj, const JsonWhere& where, const std::string& key,
                              bool optional) {
  static const Json kEmpty = Json::array();
  json_require_object(obj, where);
  auto it = obj.find(key);
  if (it == obj.end()) {
    if (optional) return kEmpty;
    json_fail(where, "missing required key \"" + key + "\"");
  }
  if (!it->is_array()) json_fail(where / key, "expected an array, found " + it->dump());
  return *it;
}

Json json_unknown_members(const Json& obj, const JsonWhere& where,
                          std::initializer_list<const char*> known,
                          std::vector<std::string>* warnings) {
  Json extra = Json::object();
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    bool ok = false;
    for (const char* k : known) ok = ok || it.key() == k;
    if (!ok) {
      extra[it.key()] = it.value();
      if (warnings)
        warnings->push_back((where / it.key()).str() + ": unknown key, kept and ignored");
    }
  }
  return extra;
}

}  // namespace fralab
