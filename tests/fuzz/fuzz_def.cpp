//! libFuzzer target for read_def (.def handle transforms). An accepted file must give at least one
//! finite affine 4x4 matrix, and write_def followed by read_def must give the same matrices, bit for bit.

#include <cmath>

#include "fuzz_input.h"
#include "msdeform/core/region.h"

using namespace msd;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = fuzz::write_input(data, size, ".def");
  std::vector<Mat4> transforms;
  if (!fuzz::reads([&] { transforms = read_def(path); })) return 0;
  fuzz::check(!transforms.empty(), "an accepted .def has no matrix");
  for (const Mat4& T : transforms) {
    fuzz::check(T.allFinite(), "a non-finite matrix was returned");
    fuzz::check(std::abs(T(3, 3) - 1) <= 1e-9 && T.row(3).head<3>().cwiseAbs().maxCoeff() <= 1e-9,
                "a matrix that is not affine was returned");
  }
  const std::string copy = fuzz::scratch_path(".def");
  write_def(transforms, copy);
  fuzz::check(read_def(copy) == transforms, "the transforms written as .def do not read back the same");
  return 0;
}
