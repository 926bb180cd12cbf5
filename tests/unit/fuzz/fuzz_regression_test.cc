// Every fuzz corpus input and every input that once crashed a reader (tests/fuzz/regressions),
// replayed through the same targets as the fuzzers (tests/fuzz/targets.h) in the ordinary build:
// each is read or refused with an InputError, nothing else escapes. Two inputs that crash an
// unguarded reader are made here: a tape event claiming 0x7fffffff bytes, a model nested 200,000
// deep.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "targets.h"

namespace {

namespace fs = std::filesystem;
const std::string kFuzzDir = std::string(FRALAB_SOURCE_DIR) + "/tests/fuzz";

std::vector<uint8_t> bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(FuzzRegression, EveryCorpusAndRegressionInputIsReadOrRefusedCleanly) {
  int n = 0;
  for (const char* reader :
       {"tape", "model", "frd", "csv", "tfns", "series", "schedule", "shapes"}) {
    for (const char* set : {"corpus", "regressions"}) {
      const fs::path dir = fs::path(kFuzzDir) / set / reader;
      if (!fs::exists(dir)) continue;
      for (const auto& f : fs::directory_iterator(dir)) {
        const auto b = bytes(f.path());
        EXPECT_NO_THROW(fralab::fuzz::run(reader, b.data(), b.size())) << f.path();
        ++n;
      }
    }
  }
  EXPECT_GE(n, 7);  // at least a seed per reader
}

TEST(FuzzRegression, TheTwoKnownCrashesAreRefusedWithAnInputError) {
  // A tape whose first event claims 0x7fffffff bytes of data.
  std::vector<uint8_t> tape = {0xED, 0xA1, 0xDA, 0x01, 0, 0, 0, 0, 0, 0,  0,    0,    0,    0,
                               0,    0,    0,    0,    0, 0, 0, 0, 0, 11, 0x7f, 0xff, 0xff, 0xff};
  for (char c : std::string("FRALAB_TAPE")) tape.push_back(uint8_t(c));
  EXPECT_EQ(fralab::fuzz::run("tape", tape.data(), tape.size()), 1);  // 1: refused
  const std::string deep = std::string(200000, '[') + std::string(200000, ']');
  EXPECT_EQ(fralab::fuzz::run("model", reinterpret_cast<const uint8_t*>(deep.data()), deep.size()),
            1);
}

}  // namespace
