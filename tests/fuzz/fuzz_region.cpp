//! libFuzzer target for the region readers, chosen at compile time by MSD_FUZZ_EXTENSION: ".sel"
//! (read_sel) or ".dmat" (read_dmat_groups). The first byte of the input is the mesh's vertex count
//! (0 to 255), the rest is the file. An accepted file must give one valid code per vertex and at
//! most as many handles as vertices; write_sel must refuse it exactly when validate() does, and otherwise
//! read_sel must give the same codes back.

#include "fuzz_input.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/region.h"

using namespace msd;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const int num_vertices = data[0];
  const std::string path = fuzz::write_input(data + 1, size - 1, MSD_FUZZ_EXTENSION);
  Region region;
  if (!fuzz::reads([&] {
        region = std::string(MSD_FUZZ_EXTENSION) == ".sel" ? read_sel(path, num_vertices)
                                                            : read_dmat_groups(path, num_vertices);
      }))
    return 0;
  fuzz::check(region.num_vertices() == num_vertices, "the region does not have one code per vertex");
  fuzz::check(region.num_handles() <= num_vertices, "more handles than vertices");
  for (int v = 0; v < num_vertices; ++v)
    fuzz::check(region.code(v) >= 0 && region.handle_of(v) < region.num_handles(),
                "vertex " + std::to_string(v) + " has a bad code");

  // write_sel refuses exactly what validate() refuses (a skipped handle code); the rest reads back the same.
  bool valid = true;
  try {
    region.validate(num_vertices);
  } catch (const InvalidInput&) {
    valid = false;
  }
  const std::string copy = fuzz::scratch_path(".sel");
  try {
    write_sel(region, copy);
  } catch (const InvalidInput&) {
    fuzz::check(!valid, "write_sel refused a region validate() accepts");
    return 0;
  }
  fuzz::check(valid, "write_sel wrote a region validate() refuses");
  const Region again = read_sel(copy, num_vertices);
  fuzz::check(again.codes() == region.codes(), "the region written as .sel does not read back the same");
  return 0;
}
