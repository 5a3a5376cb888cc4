#include "fuzz_input.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>

namespace msd::fuzz {
namespace {

// One folder per process, removed at exit, so parallel fuzzers and replays never share a file. The name
// is never destroyed: the exit handler that removes the folder runs after static destructors.
const std::string& folder() {
  static const std::string* dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    auto* pattern = new std::string(std::string(tmp && *tmp ? tmp : "/tmp") + "/msd-fuzz-XXXXXX");
    if (!mkdtemp(pattern->data())) fail("cannot create a scratch folder from " + *pattern);
    std::atexit([] { std::filesystem::remove_all(*dir); });
    return pattern;
  }();
  return *dir;
}

}  // namespace

std::string& last_refusal() {
  static std::string message;
  return message;
}

std::string scratch_path(const std::string& extension) { return folder() + "/output" + extension; }

std::string write_input(const uint8_t* data, size_t size, const std::string& extension) {
  const std::string path = folder() + "/input" + extension;
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || (size && std::fwrite(data, 1, size, f) != size) || std::fclose(f) != 0) fail("cannot write " + path);
  return path;
}

void fail(const std::string& what) {
  std::cerr << "fuzz property failed: " << what << std::endl;
  std::abort();
}

}  // namespace msd::fuzz
