// JSON reading with locations: every value read from a user file knows its file and JSON-pointer
// path, so that a bad value is reported as "FILE: /inputs/0/actuator/tf/poles/1: what is wrong".
// This is the one place fralab turns JSON into numbers; model, frd and tf readers all use it.
#pragma once

#include <initializer_list>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "fralab/core/error.h"

namespace fralab {

using Json = nlohmann::json;

/// Where a JSON value sits: the file (or other source name) and its JSON-pointer path.
struct JsonWhere {
  std::string file;
  std::string path;  // "" is the document root
  JsonWhere operator/(const std::string& key) const { return {file, path + "/" + key}; }
  JsonWhere operator/(size_t index) const { return {file, path + "/" + std::to_string(index)}; }
  std::string str() const { return file + ": " + (path.empty() ? "/" : path); }
};

/// Throws InputError "FILE: PATH: message".
[[noreturn]] void json_fail(const JsonWhere& where, const std::string& message);

/// Deepest nesting a fralab JSON file may have (fralab's own files use fewer than 8 levels).
inline constexpr int kMaxJsonDepth = 64;

/// Parses a JSON file; syntax errors name the file, line and column; nesting deeper than
/// kMaxJsonDepth is refused naming the file (a hostile file cannot exhaust the stack).
Json json_load_file(const std::string& file);
/// The same for a text (a message, a flag); errors name `where`.
Json json_parse_text(const std::string& text, const std::string& where);

/// Writes pretty JSON (2-space indent, trailing newline); throws InputError when it cannot.
void json_save_file(const std::string& file, const Json& j);

/// Requires `obj` to be an object.
void json_require_object(const Json& obj, const JsonWhere& where);

/// The member `key` of object `obj`; InputError naming the key when missing.
const Json& json_member(const Json& obj, const JsonWhere& where, const std::string& key);

/// A finite number; InputError otherwise (strings, null, NaN are refused).
double json_number(const Json& v, const JsonWhere& where);

/// true or false; InputError naming `where` otherwise.
bool json_bool(const Json& v, const JsonWhere& where);

/// An integer that fits int64_t; InputError naming `where` otherwise (1.5, "3", 2^63 refused).
int64_t json_integer(const Json& v, const JsonWhere& where);

/// A string; InputError naming `where` otherwise.
std::string json_string(const Json& v, const JsonWhere& where);

/// A finite number member; `fallback` when absent and not required.
double json_number_member(const Json& obj, const JsonWhere& where, const std::string& key);
double json_number_member(const Json& obj, const JsonWhere& where, const std::string& key,
                          double fallback);

/// A string member (required).
std::string json_string_member(const Json& obj, const JsonWhere& where, const std::string& key);

/// An array member (required unless `optional`, then an empty array when absent).
const Json& json_array_member(const Json& obj, const JsonWhere& where, const std::string& key,
                              bool optional = false);

/// Appends "FILE: PATH/KEY: unknown key ... (ignored)" to `warnings` for each key of `obj` not in
/// `known`, and returns those members so that they can be kept and written back.
Json json_unknown_members(const Json& obj, const JsonWhere& where,
                          std::initializer_list<const char*> known,
                          std::vector<std::string>* warnings);

}  // namespace fralab
