#include "support/scratch.hpp"

#include <filesystem>

namespace vpm::test {

std::string fresh_dir(const std::string& name) {
  const std::string d = std::string(VPM_TEST_TMP) + "/" + name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

}  // namespace vpm::test
