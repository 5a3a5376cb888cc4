//! Replays fuzz inputs through a libFuzzer target without libFuzzer, so the seed corpus and every crash
//! input found run as ordinary tests in every build (g++ included):
//!   replay_<target> FILE_OR_FOLDER...
//! Each file is one input; folders are read in name order. Exits 0 after every input ran; a failed
//! property aborts (fuzz_input.h) and a crash is a crash, both failing the test.

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    if (fs::is_directory(argv[i])) {
      std::vector<fs::path> files;
      for (const auto& entry : fs::directory_iterator(argv[i]))
        if (entry.is_regular_file()) files.push_back(entry.path());
      std::sort(files.begin(), files.end());
      inputs.insert(inputs.end(), files.begin(), files.end());
    } else if (fs::is_regular_file(argv[i])) {
      inputs.emplace_back(argv[i]);
    } else {
      std::cerr << "replay: " << argv[i] << " is neither a file nor a folder\n";
      return 2;
    }
  }
  if (inputs.empty()) {
    std::cerr << "replay: no inputs (usage: replay FILE_OR_FOLDER...)\n";
    return 2;
  }
  size_t accepted = 0;
  for (const fs::path& path : inputs) {
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::cout << path.filename().string() << " (" << bytes.size() << " bytes): " << std::flush;
    msd::fuzz::last_refusal().clear();
    LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
    const std::string& refusal = msd::fuzz::last_refusal();
    if (refusal.empty()) ++accepted;
    std::cout << (refusal.empty() ? "read" : "refused: " + refusal) << std::endl;
  }
  std::cout << "replay: " << inputs.size() << " inputs ran, " << accepted << " read, " << inputs.size() - accepted
            << " refused" << std::endl;
  return 0;
}
