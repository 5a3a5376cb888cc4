#pragma once
//! \file What the libFuzzer targets under tests/fuzz share: the input as a file (every msdeform reader
//! takes a path, so the fuzzers test exactly what the command line and the library run), the errors a
//! reader may throw, and a check that stops the run loudly when a property fails.

#include <cstddef>
#include <cstdint>
#include <string>

#include "msdeform/core/errors.h"

namespace msd::fuzz {

//! Writes the fuzzer's bytes to a private scratch file named "input<extension>" and returns its path.
std::string write_input(const uint8_t* data, size_t size, const std::string& extension);

//! A second scratch path ("output<extension>") in the same private folder, for round trips.
std::string scratch_path(const std::string& extension);

//! Prints the property that failed and aborts, so libFuzzer keeps the input as a crash.
[[noreturn]] void fail(const std::string& what);

//! The message of the last refusal by reads() ("" when none since it was cleared): the replay prints it
//! after each input, so its log shows what each seed exercised.
std::string& last_refusal();

//! Runs read(); returns true if it finished, false if it refused the input with msdeform's InvalidInput
//! or TopologyError (the documented way to refuse a bad file). Any other exception escapes: a bad_alloc,
//! a length_error or an out_of_range from a reader is a bug this harness exists to find.
template <class Read>
bool reads(Read&& read) {
  try {
    read();
    return true;
  } catch (const InvalidInput& e) {
    last_refusal() = e.what();
  } catch (const TopologyError& e) {
    last_refusal() = e.what();
  }
  return false;
}

//! fail(what) unless condition holds.
inline void check(bool condition, const std::string& what) {
  if (!condition) fail(what);
}

}  // namespace msd::fuzz
