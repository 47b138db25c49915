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

TEST_CASE("json numbers dump as their parse dumps") {
  // integers below 1e15 exactly, the rest to 10 significant digits; a value whose 10 digits are
  // an integer is written as that integer (fuzz_json found "5.555555556e+13" -> "55555555560000")
  for (const double v : {55555555555550.02, 0.99999999999, 12345678901234.0, 1.5e15 + 0.5, 1e300, -2.5e-7,
                         123456.0, 9999999999.7}) {
    const std::string once = Json(v).dump(-1);
    CHECK(Json::parse(once).dump(-1) == once);
  }
  CHECK(Json(55555555555550.02).dump(-1) == "55555555560000");
  CHECK(Json(12345678901234.0).dump(-1) == "12345678901234");
  CHECK(Json(0.99999999999).dump(-1) == "1");
  CHECK(Json(0.1).dump(-1) == "0.1");
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
