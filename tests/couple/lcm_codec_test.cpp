// The runtime LCM parser/codec against lcm-gen's generated C++ code (a second tool):
// equal fingerprints, our decoder reads lcm-gen's bytes as the values lcm-gen was given,
// our encoder reproduces lcm-gen's bytes exactly, and lcm-gen decodes what we encode.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "../common/scratch_dir.hpp"
#include "../common/shell_quote.hpp"
#include "core/errors.hpp"
#include "couple/lcm_codec.hpp"
#include "couple/lcm_types.hpp"

using builtscene::couple::LcmCodec;
using builtscene::couple::TypeRegistry;
using nlohmann::json;
using builtscene::testing::shell_quote;

namespace {

const std::string kDir = std::string(BUILTSCENE_SOURCE_DIR) + "/tests/couple/lcm/";

TypeRegistry load() {
  TypeRegistry t;
  t.parse_file(kDir + "bstest.lcm");
  t.parse_file(kDir + "bsother.lcm");
  t.validate();
  return t;
}

std::string run(const std::string& cmd) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return out;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  EXPECT_EQ(pclose(p), 0) << cmd;
  return out;
}

std::vector<uint8_t> bytes(const std::string& s) { return {s.begin(), s.end()}; }

// The lcm-gen helper program, quoted for the shell.
std::string helper() { return shell_quote(LCMGEN_HELPER); }

// The same values lcmgen_helper.cpp fills in, written out independently.
json primitives(int k) {
  return {{"i8", -5 - k}, {"i16", -300 + k}, {"i32", 70000 + k}, {"i64", -1234567890123LL - k},
          {"f", 1.5 + k}, {"d", 3.141592653589793 * (k + 1)}, {"s", "hello" + std::to_string(k)},
          {"b", k % 2 == 0}, {"by", 250 - k}};
}

json arrays(int n) {
  json a = {{"n", n}, {"m", 2}, {"fixed", {-1.0, -0.75, -0.5}},
            {"grid", {{-100000000000LL, -99999999999LL, -99999999998LL}, {-99999999990LL, -99999999989LL, -99999999988LL}}},
            {"var", json::array()}, {"names", json::array()}, {"blob", {0, 255}},
            {"flags", {{true, false}, {false, true}}}, {"mixed", json::array()}};
  for (int i = 0; i < n; ++i) {
    a["var"].push_back(0.5 * i);
    a["names"].push_back(std::string(static_cast<std::size_t>(i), 'x'));
    a["mixed"].push_back({i, -i});
  }
  return a;
}

json nested() {
  return {{"step", 17}, {"p", primitives(0)}, {"count", 2}, {"items", {arrays(0), arrays(3)}},
          {"pair", {primitives(1), primitives(2)}}, {"pt", {{"x", -2.5}, {"y", 1e-300}}}};
}

const std::map<std::string, json>& samples() {
  static const std::map<std::string, json> s = {
      {"bstest.primitives_t", primitives(0)}, {"bstest.arrays_t", arrays(3)}, {"bstest.nested_t", nested()}};
  return s;
}

}  // namespace

TEST(LcmCodec, FingerprintsEqualLcmGen) {
  const TypeRegistry t = load();
  std::istringstream in(run(helper() + " fingerprints"));
  std::string name;
  unsigned long long hash = 0;
  int n = 0;
  while (in >> name >> hash) {
    EXPECT_EQ(t.fingerprint(name), hash) << name;
    ++n;
  }
  EXPECT_EQ(n, 4);
}

TEST(LcmCodec, DecodesLcmGenBytesAndReencodesThemExactly) {
  const TypeRegistry t = load();
  for (const auto& [type, expected] : samples()) {
    const auto theirs = bytes(run(helper() + " make " + type));
    ASSERT_GT(theirs.size(), 8u) << type;
    LcmCodec codec(t, type);
    const json decoded = codec.decode(theirs);
    EXPECT_EQ(decoded, expected) << type << "\n" << decoded.dump() << "\n" << expected.dump();
    EXPECT_EQ(codec.encode(decoded), theirs) << type;
    EXPECT_EQ(codec.encode(expected), theirs) << type;
  }
}

TEST(LcmCodec, LcmGenDecodesWhatWeEncode) {
  const TypeRegistry t = load();
  const auto dir = builtscene::testing::scratch_dir("lcm_codec");
  for (const auto& [type, value] : samples()) {
    LcmCodec codec(t, type);
    json v = value;
    if (type == "bstest.primitives_t") v["s"] = "a different string";  // not the helper's sample
    const auto ours = codec.encode(v);
    const std::string file = (dir / "ours.bin").string();
    std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(ours.data()),
                                                static_cast<std::streamsize>(ours.size()));
    const auto back = bytes(run(helper() + " roundtrip " + type + " < " + shell_quote(file)));
    EXPECT_EQ(back, ours) << type;
  }
}

TEST(LcmCodec, RejectsWrongShapesAndForeignBytes) {
  const TypeRegistry t = load();
  LcmCodec codec(t, "bstest.arrays_t");
  json v = arrays(2);
  v["fixed"] = {1.0, 2.0};
  EXPECT_THROW(codec.encode(v), builtscene::InputError);
  v = arrays(2);
  v.erase("grid");
  try {
    codec.encode(v);
    FAIL() << "missing member accepted";
  } catch (const builtscene::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("grid"), std::string::npos) << e.what();
  }
  v = arrays(2);
  v.erase("n");  // a size member may be left out: taken from the array
  EXPECT_EQ(codec.decode(codec.encode(v)), arrays(2));
  LcmCodec other(t, "bstest.primitives_t");
  EXPECT_THROW(codec.decode(other.encode(primitives(0))), builtscene::InputError);
  auto truncated = codec.encode(arrays(2));
  truncated.resize(truncated.size() - 3);
  EXPECT_THROW(codec.decode(truncated), builtscene::InputError);
}

TEST(LcmTypes, SyntaxErrorsNameFileAndLine) {
  TypeRegistry t;
  try {
    t.parse_text("package p;\nstruct a {\n  double x\n  int32_t y;\n}\n", "bad.lcm");
    FAIL();
  } catch (const builtscene::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.lcm:4"), std::string::npos) << e.what();
  }
  TypeRegistry u;
  EXPECT_THROW(u.parse_text("struct b { float v[n]; }", "b.lcm"), builtscene::InputError);  // n undeclared
  TypeRegistry w;
  w.parse_text("struct c { mystery_t m; }", "c.lcm");
  EXPECT_THROW(w.validate(), builtscene::InputError);
}
