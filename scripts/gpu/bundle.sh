#!/usr/bin/env bash
# Packs what a GPU machine needs to run this build of vpm (docs/gpu.md): the program, the
# library, the test and benchmark binaries with their CTest files, every shared library they
# load that a bare machine may lack (compressed), an OpenCL vendor file for NVIDIA's driver,
# Colin27 and the AAL atlas from Debian's mricron-data, and run.sh. The folder is ignored by git
# and travels with the device tool's `carry`.
#   usage: scripts/gpu/bundle.sh [BUILD_DIR (build)] [OUT (.gpu)]
# then, with the device tool: run `bash .gpu/run.sh` with carry [".gpu"].
set -euo pipefail
cd "$(dirname "$0")/../.."
B=${1:-build}
O=${2:-.gpu}
[[ -x $B/vpm && -f $B/libvpm.so ]] || { echo "bundle.sh: $B has no vpm build (bash scripts/build.sh -DVPM_BUILD_TESTS=ON -DVPM_BUILD_BENCH=ON)" >&2; exit 2; }
grep -qx "/$O/" .git/info/exclude 2>/dev/null || echo "/$O/" >> .git/info/exclude
rm -rf "$O" && mkdir -p "$O/build/tests" "$O/build/bench" "$O/lib" "$O/icd" "$O/mricron" "$O/bin"
cp -a "$B/vpm" "$B/libvpm.so" "$B/CTestTestfile.cmake" "$O/build/"
cp -a "$B"/tests/*.cmake "$O/build/tests/"
for t in "$B"/tests/test_*; do [[ -f $t && -x $t ]] && cp -a "$t" "$O/build/tests/"; done
[[ -f $B/bench/CTestTestfile.cmake ]] && cp -a "$B/bench/CTestTestfile.cmake" "$O/build/bench/"
for b in solver harmonic sphere_map volume_map register pairs; do
  [[ -x $B/bench/vpm_bench_$b ]] && cp -a "$B/bench/vpm_bench_$b" "$O/build/bench/"
done
# the shared libraries of everything above, less the C/C++ runtime every Linux has
shopt -s nullglob
{ ldd "$B/vpm" "$B/libvpm.so" "$O"/build/tests/test_* "$O"/build/bench/vpm_bench_* 2>/dev/null || true; } |
  awk '$2 == "=>" && $3 ~ /^\// {print $3}' | sort -u |
  grep -Ev '/(libc|libm|libstdc\+\+|libgcc_s|libpthread|libdl|librt|ld-linux[^/]*)\.so' |
  grep -v "/$B/" | while read -r l; do cp -L "$l" "$O/lib/"; done
tar cJf "$O/libs.tar.xz" -C "$O" lib && rm -rf "$O/lib"
# the test binaries too: over a hundred of them pass the carry limit (64 MiB) uncompressed
tar -I "xz -T0" -cf "$O/tests.tar.xz" -C "$O/build" tests && rm -rf "$O/build/tests"
echo libnvidia-opencl.so.1 > "$O/icd/nvidia.icd"
T=/usr/share/mricron/templates
cp "$T/ch2bet.nii.gz" "$T/ch2.nii.gz" "$T"/aal.nii* "$O/mricron/"
cp /usr/bin/time "$O/bin/"
cp scripts/gpu/run.sh "$O/run.sh"
du -sh "$O"
echo "bundle.sh: device tool: run command 'bash $O/run.sh' with carry [\"$O\"] (about 4 minutes on an H200)"
