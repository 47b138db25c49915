#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <sstream>

#include "vpm/error.hpp"
#include "vpm/json.hpp"

using namespace vpm;

TEST_CASE("json round trip keeps order, escapes and numbers") {
  Json j = Json::object();
  j["b"] = 1.5;
  j["a"] = "x\"y\n";
  j["n"] = Json();
  j["nan"] = std::nan("");
  j["arr"].push_back(1);
  j["arr"].push_back(true);
  const std::string s = j.dump(-1);
  CHECK(s == R"({"b":1.5,"a":"x\"y\n","n":null,"nan":null,"arr":[1,true]})");
  const Json p = Json::parse(j.dump(2));
  CHECK(p.find("b")->number() == 1.5);
  CHECK(p.find("a")->string() == "x\"y\n");
  CHECK(p.find("arr")->size() == 2);
  CHECK_THROWS(Json::parse("{\"a\": }"));
  CHECK_THROWS(Json::parse("[1, 2"));
}

TEST_CASE("json files are written atomically") {
  const std::string path = std::string(VPM_TEST_TMP) + "/report.json";
  Json j;
  j["x"] = 3;
  write_json_file(path, j);
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  CHECK(Json::parse(ss.str()).find("x")->number() == 3);
  CHECK_THROWS_AS(write_json_file("/nonexistent-dir/r.json", j), InputError);
}
