// fuzz_<target>_replay FILE|FOLDER...: feeds every file (folders: their files, recursively, in
// name order) to the target's LLVMFuzzerTestOneInput, as libFuzzer would, without libFuzzer: the
// normal (gcc) build replays the seeds and the kept crash inputs of fuzz/regressions/ this way.
// Each file's name is printed before it runs, so a crash names its input. As in scripts/fuzz.sh,
// an input that runs for more than 10 s is a hang (SIGALRM ends the replay) and, outside ASan
// (which reserves terabytes of address space), the process may hold at most 2 GiB (a huge
// allocation throws std::bad_alloc, which the target reports). Exits 1 when given no file at all
// (a replay that tests nothing must not pass).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sys/resource.h>
#include <unistd.h>
#include <vector>

#include "fuzz_target.hpp"

namespace fs = std::filesystem;

#if defined(__SANITIZE_ADDRESS__)
#define VPM_REPLAY_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VPM_REPLAY_ASAN 1
#endif
#endif

int main(int argc, char** argv) {
  std::vector<fs::path> files;
  for (int i = 1; i < argc; ++i) {
    const fs::path arg = argv[i];
    if (fs::is_directory(arg)) {
      for (const auto& e : fs::recursive_directory_iterator(arg))
        if (e.is_regular_file()) files.push_back(e.path());
    } else if (fs::is_regular_file(arg)) {
      files.push_back(arg);
    } else {
      std::fprintf(stderr, "replay: %s: no such file or folder\n", argv[i]);
      return 1;
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) {
    std::fprintf(stderr, "replay: no input files\n");
    return 1;
  }
#ifndef VPM_REPLAY_ASAN
  const rlimit memory{rlim_t(2) << 30, rlim_t(2) << 30};
  setrlimit(RLIMIT_AS, &memory);
#endif
  for (const fs::path& f : files) {
    std::printf("replay %s\n", f.c_str());
    std::fflush(stdout);
    alarm(10);
    std::ifstream in(f, std::ios::binary);
    const std::vector<char> data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(data.data()), data.size());
  }
  std::printf("replay: %zu inputs, none crashed\n", files.size());
  return 0;
}
