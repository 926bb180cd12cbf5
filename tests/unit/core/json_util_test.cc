// JSON reading (core/json_util.h): a file nested deeper than kMaxJsonDepth is refused naming the
// file (200,000 levels would overflow a recursive reader's stack), ordinary files read.
#include "fralab/core/json_util.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace fralab {
namespace {

std::string write(const std::string& name, const std::string& text) {
  const std::string p = (std::filesystem::temp_directory_path() /
                         ("json_util_test_" + std::to_string(getpid()) + "_" + name))
                            .string();
  std::ofstream(p) << text;
  return p;
}

// Typed values: the value when it is of the type, else an error naming the place and the value.
TEST(JsonUtil, TypedValuesAreReadOrRefusedNamingThePlace) {
  const JsonWhere w{"f.json", "/k"};
  EXPECT_EQ(json_bool(Json(true), w), true);
  EXPECT_EQ(json_integer(Json(-7), w), -7);
  EXPECT_EQ(json_integer(Json(uint64_t(INT64_MAX)), w), INT64_MAX);
  EXPECT_EQ(json_string(Json("x"), w), "x");
  using ::testing::HasSubstr;
  using ::testing::ThrowsMessage;
  EXPECT_THAT([&] { json_bool(Json(1), w); },
              ThrowsMessage<InputError>(HasSubstr("f.json: /k: expected true or false, found 1")));
  for (const Json& bad : {Json(1.5), Json("3"), Json(uint64_t(INT64_MAX) + 1), Json(nullptr)})
    EXPECT_THAT(
        [&] { json_integer(bad, w); },
        ThrowsMessage<InputError>(HasSubstr("/k: expected an integer, found " + bad.dump())));
  EXPECT_THAT([&] { json_string(Json(2), w); },
              ThrowsMessage<InputError>(HasSubstr("/k: expected a string, found 2")));
}

TEST(JsonUtil, NestingBeyondTheLimitIsRefusedNamingTheFile) {
  const std::string deep = write("deep.json", std::string(200000, '[') + std::string(200000, ']'));
  try {
    json_load_file(deep);
    ADD_FAILURE() << "200,000 levels accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("deep.json: JSON nested deeper than 64 levels"));
  }
  const std::string at_limit =
      write("limit.json", std::string(kMaxJsonDepth, '[') + std::string(kMaxJsonDepth, ']'));
  EXPECT_NO_THROW(json_load_file(at_limit));
  const std::string over =
      write("over.json", std::string(kMaxJsonDepth + 1, '[') + std::string(kMaxJsonDepth + 1, ']'));
  EXPECT_THROW(json_load_file(over), InputError);
  const Json j = json_load_file(write("ok.json", R"({"a": [1, {"b": 2}]})"));
  EXPECT_EQ(j["a"][1]["b"], 2);
  EXPECT_THROW(json_load_file(write("bad.json", "{\"a\": ")), InputError);
}

}  // namespace
}  // namespace fralab
