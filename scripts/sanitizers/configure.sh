# Sourced by scripts/sanitize.sh and scripts/fuzz.sh: configures the clang ASan + UBSan tree
# $SAN_DIR with the fuzz targets and the tests (extra arguments go to cmake). -O1: ASan's
# recommended level; line tables only (a report's stack names functions, files and lines; full
# debug information costs a quarter more compile time); no NDEBUG, so Eigen's bounds assertions
# are on. Ninja, where the tree is new or already Ninja's: it builds a list of targets in
# parallel (CMake's Makefiles build them one after another).
san_configure() {
  local generator=()
  if command -v ninja >/dev/null &&
     { [[ ! -f $SAN_DIR/CMakeCache.txt ]] || grep -q '^CMAKE_GENERATOR:INTERNAL=Ninja$' "$SAN_DIR/CMakeCache.txt"; }; then
    generator=(-G Ninja)
  fi
  cmake -S . -B "$SAN_DIR" "${generator[@]}" -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" -DVPM_SANITIZE=ON -DVPM_BUILD_FUZZ=ON \
    -DVPM_BUILD_TESTS=ON -DVPM_BUILD_BENCH=OFF "$@" >/dev/null
}
