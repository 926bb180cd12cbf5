// One libFuzzer executable per reader (FRALAB_FUZZ_READER names it at compile time).
#include "targets.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fralab::fuzz::run(FRALAB_FUZZ_READER, data, size);  // read or refused: both are clean
  return 0;
}
