#!/usr/bin/env bash
# Installs the build tree into a scratch prefix and uses it as a tool would (ctest test install_and_examples):
#   1. the layout: headers under include/msdeform/, the CMake package, libraries, the program (--version);
#   2. examples/ configured against the package, built and run with the library's own flags; built with
#      -march=native too, where they must either run (the same Eigen settings) or stop at compile time
#      with the message that names the fix;
#   3. a program linking msdeform and another Eigen library (built with Eigen's defaults) frees the
#      other library's blocks (msdeform forces no Eigen define on its users);
#   4. a translation unit with other Eigen settings than the library's stops at compile time, naming them;
#   5. add_subdirectory() of the source tree configures the libraries only (no tests or benchmarks);
#   6. the README's first ```python block runs against the installed module.
# Usage: check_install.sh SOURCE_DIR BUILD_DIR PYTHON   (PYTHON: ON when the build has the Python module)
set -euo pipefail
src="$1"
build="$2"
with_python="$3"
work="$build/install-check"
prefix="$work/prefix"
rm -rf "$work"
mkdir -p "$work"
say() { echo "install-check: $*"; }
fail() { echo "install-check: FAILED: $*" >&2; exit 1; }

# 1. Install and look at what landed.
cmake --install "$build" --prefix "$prefix" >"$work/install.log"
for f in include/msdeform/version.h include/msdeform/core/mesh.h include/msdeform/reconstruction/catalogue.h \
         lib/cmake/msdeform/msdeformConfig.cmake lib/cmake/msdeform/msdeformConfigVersion.cmake \
         lib/cmake/msdeform/msdeformTargets.cmake bin/msdeform share/doc/msdeform/LICENSE; do
  [ -e "$prefix/$f" ] || fail "cmake --install did not install $f"
done
if find "$prefix/include" -name '*.cpp' | grep -q .; then fail "sources installed under include/"; fi
if [ -e "$prefix/include/msdeform/apps" ] || [ -e "$prefix/include/core" ]; then fail "headers outside include/msdeform/<module>"; fi
version=$(env -u LD_LIBRARY_PATH "$prefix/bin/msdeform" --version | head -1)
[ "$version" = "msdeform $(sed -n 's/#define MSD_VERSION_STRING "\(.*\)"/\1/p' "$build/include/msdeform/version.h")" ] ||
  fail "installed msdeform --version printed '$version'"
say "installed $(find "$prefix" -type f | wc -l) files; $version"

# 2. The examples against the package: with the library's flags they must run; with -march=native they
#    must run or stop with the ABI message (Eigen's settings under -march=native may differ from the
#    library's: 32-byte alignment with AVX).
abi_message="Eigen's alignment here differs from msdeform's libraries"
for flavour in plain native; do
  flags=""
  [ "$flavour" = native ] && flags="-march=native"
  cmake -S "$src/examples" -B "$work/examples-$flavour" -G Ninja -DCMAKE_BUILD_TYPE=Release \
        -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_CXX_FLAGS="$flags" >"$work/examples-$flavour.log" 2>&1 ||
    { cat "$work/examples-$flavour.log"; fail "examples ($flavour) did not configure against the package"; }
  if cmake --build "$work/examples-$flavour" >>"$work/examples-$flavour.log" 2>&1; then
    (cd "$work/examples-$flavour" && ./one_edit && ./frame_loop) || fail "an example ($flavour) exited non-zero"
    say "examples built ($flavour) and ran"
  elif [ "$flavour" = native ] && grep -q "$abi_message" "$work/examples-$flavour.log"; then
    say "examples ($flavour) stopped at compile time with the ABI message (the library's Eigen settings differ)"
  else
    cat "$work/examples-$flavour.log"
    fail "examples ($flavour) did not build"
  fi
done

# 3. A program that links msdeform and another Eigen library built with the defaults frees both's blocks.
cmake -S "$src/tests/install/mixed" -B "$work/mixed" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_PREFIX_PATH="$prefix" >"$work/mixed.log" 2>&1 && cmake --build "$work/mixed" >>"$work/mixed.log" 2>&1 ||
  { cat "$work/mixed.log"; fail "the program mixing msdeform and another Eigen library did not build"; }
"$work/mixed/mixed" || fail "the program mixing msdeform and another Eigen library crashed or failed"
say "a program with msdeform and another Eigen library ran"

# 4. Other Eigen settings than the library's are refused at compile time, naming the library's flags:
#    an instruction set with another alignment, an explicit EIGEN_MAX_ALIGN_BYTES, another index type,
#    and AddressSanitizer (under which Eigen aligns heap blocks by hand).
heap=$(sed -n 's/#define MSD_EIGEN_DEFAULT_ALIGN_BYTES \([0-9]*\)/\1/p' "$prefix/include/msdeform/config.h")
[ -n "$heap" ] || fail "include/msdeform/config.h does not record Eigen's heap alignment"
other_isa="-mavx"
[ "$heap" = 16 ] || other_isa="-mno-avx"
echo '#include <msdeform/core/types.h>
int main() { return 0; }' >"$work/abi.cpp"
# flags|the message expected (a 4-byte Eigen::Index compiled and linked, then crashed in a destructor)
cases=("$other_isa|$abi_message" "-DEIGEN_MAX_ALIGN_BYTES=64|$abi_message"
       "-DEIGEN_DEFAULT_DENSE_INDEX_TYPE=int|Eigen's index type here differs")
[ "$heap" = 16 ] && cases+=("-fsanitize=address|add -DEIGEN_MALLOC_ALREADY_ALIGNED=1")  # malloc-allocating library
for case in "${cases[@]}"; do
  flags="${case%%|*}"
  expected="${case#*|}"
  if c++ -std=c++17 $flags -I"$prefix/include" -I/usr/include/eigen3 -c "$work/abi.cpp" -o "$work/abi.o" \
       2>"$work/abi.log"; then
    fail "a translation unit with $flags compiled against msdeform (Eigen heap alignment $heap)"
  fi
  grep -qF "$expected" "$work/abi.log" || { cat "$work/abi.log"; fail "no clear Eigen settings message for $flags"; }
done
c++ -std=c++17 -I"$prefix/include" -I/usr/include/eigen3 -c "$work/abi.cpp" -o "$work/abi.o" 2>"$work/abi.log" ||
  [ "$heap" != 16 ] || { cat "$work/abi.log"; fail "a plain translation unit did not compile against msdeform"; }
say "other Eigen settings stop at compile time with their fix"

# 5. add_subdirectory: the libraries only.
mkdir -p "$work/sub"
cat >"$work/sub/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.21)
project(consumer LANGUAGES CXX)
add_subdirectory("$src" msdeform)
add_executable(consumer main.cpp)
target_link_libraries(consumer PRIVATE msd::msdeform)
CMAKE
echo 'int main() { return 0; }' >"$work/sub/main.cpp"
cmake -S "$work/sub" -B "$work/sub-build" -G Ninja >"$work/sub.log" 2>&1 || { cat "$work/sub.log"; fail "add_subdirectory did not configure"; }
for t in test_core bench_shell msdeform_python; do
  if grep -q "build $t\b\|/$t:" "$work/sub-build/build.ninja"; then fail "add_subdirectory builds $t"; fi
done
grep -q "libmsdeform_core" "$work/sub-build/build.ninja" || fail "add_subdirectory has no msdeform_core"
say "add_subdirectory configures the libraries only"

# 6. The README's Python example against the installed module (Debian's interpreter: it has numpy).
python=/usr/bin/python3
if [ "$with_python" = ON ]; then
  site=$(ls -d "$prefix"/lib/python3*/dist-packages 2>/dev/null | head -1 || true)
  [ -n "$site" ] || fail "the Python module was built but not installed under lib/python3*/dist-packages"
  awk '/^```python/{on=1; next} on && /^```/{exit} on' "$src/README.md" >"$work/readme_example.py"
  [ -s "$work/readme_example.py" ] || fail "README.md has no \`\`\`python block"
  (cd "$work" && env -u LD_LIBRARY_PATH PYTHONPATH="$site" "$python" readme_example.py) ||
    fail "the README's Python example failed against the installed module"
  say "the README's Python example ran against $site"
else
  say "no Python module installed (MSD_BUILD_PYTHON=OFF): README example not run"
fi
say "passed"
