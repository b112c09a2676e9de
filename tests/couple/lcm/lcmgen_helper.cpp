// Built from lcm-gen's C++ output for bstest.lcm / bsother.lcm (generated at build time).
// The second tool the codec tests compare against:
//   lcmgen_helper fingerprints          -> "type hash" lines (getHash())
//   lcmgen_helper make TYPE             -> the encoded sample value of TYPE on stdout
//   lcmgen_helper roundtrip TYPE        -> decodes stdin with lcm-gen code, re-encodes to stdout
//   lcmgen_helper print TYPE            -> decodes stdin, prints a few members
#include <cstdio>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

#include "bstest/nested_t.hpp"

namespace {

bstest::primitives_t sample_primitives(int k) {
  bstest::primitives_t p;
  p.i8 = static_cast<int8_t>(-5 - k);
  p.i16 = static_cast<int16_t>(-300 + k);
  p.i32 = 70000 + k;
  p.i64 = -1234567890123LL - k;
  p.f = 1.5f + static_cast<float>(k);
  p.d = 3.141592653589793 * (k + 1);
  p.s = "hello" + std::to_string(k);
  p.b = (k % 2) == 0;
  p.by = static_cast<uint8_t>(250 - k);
  return p;
}

bstest::arrays_t sample_arrays(int n) {
  bstest::arrays_t a;
  a.n = n;
  a.m = 2;
  for (int i = 0; i < 3; ++i) a.fixed[i] = 0.25 * i - 1.0;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 3; ++j) a.grid[i][j] = 10 * i + j - 100000000000LL;
  for (int i = 0; i < n; ++i) {
    a.var.push_back(0.5f * static_cast<float>(i));
    a.names.push_back(std::string(static_cast<std::size_t>(i), 'x'));
    a.mixed.push_back({static_cast<int8_t>(i), static_cast<int8_t>(-i)});
  }
  a.blob = {0, 255};
  a.flags = {{true, false}, {false, true}};
  return a;
}

bstest::nested_t sample_nested() {
  bstest::nested_t v;
  v.step = 17;
  v.p = sample_primitives(0);
  v.count = 2;
  v.items = {sample_arrays(0), sample_arrays(3)};
  v.pair[0] = sample_primitives(1);
  v.pair[1] = sample_primitives(2);
  v.pt.x = -2.5;
  v.pt.y = 1e-300;
  return v;
}

template <typename T>
int write(const T& v) {
  std::vector<char> buf(static_cast<std::size_t>(v.getEncodedSize()));
  if (v.encode(buf.data(), 0, static_cast<int>(buf.size())) != static_cast<int>(buf.size())) return 3;
  std::fwrite(buf.data(), 1, buf.size(), stdout);
  return 0;
}

template <typename T>
int roundtrip(const std::vector<char>& in) {
  T v;
  const int used = v.decode(in.data(), 0, static_cast<int>(in.size()));
  if (used != static_cast<int>(in.size())) {
    std::fprintf(stderr, "lcm-gen decode failed: %d of %zu bytes\n", used, in.size());
    return 4;
  }
  return write(v);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  const std::string cmd = argv[1];
  if (cmd == "fingerprints") {
    std::printf("bstest.primitives_t %llu\n", static_cast<unsigned long long>(bstest::primitives_t::getHash()));
    std::printf("bstest.arrays_t %llu\n", static_cast<unsigned long long>(bstest::arrays_t::getHash()));
    std::printf("bstest.nested_t %llu\n", static_cast<unsigned long long>(bstest::nested_t::getHash()));
    std::printf("bsother.point_t %llu\n", static_cast<unsigned long long>(bsother::point_t::getHash()));
    return 0;
  }
  if (argc < 3) return 2;
  const std::string type = argv[2];
  if (cmd == "make") {
    if (type == "bstest.primitives_t") return write(sample_primitives(0));
    if (type == "bstest.arrays_t") return write(sample_arrays(3));
    if (type == "bstest.nested_t") return write(sample_nested());
    return 2;
  }
  if (cmd == "roundtrip") {
    std::vector<char> in((std::istreambuf_iterator<char>(std::cin)), std::istreambuf_iterator<char>());
    if (type == "bstest.primitives_t") return roundtrip<bstest::primitives_t>(in);
    if (type == "bstest.arrays_t") return roundtrip<bstest::arrays_t>(in);
    if (type == "bstest.nested_t") return roundtrip<bstest::nested_t>(in);
    return 2;
  }
  return 2;
}
