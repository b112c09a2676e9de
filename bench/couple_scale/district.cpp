// The district aggregator of the scale benchmark (bench/couple_scale.sh): one model that
// reads every building's STRUCTURE_i (wsc.response_t) and publishes DISTRICT, also a
// wsc.response_t: mean D, mean V and the largest |A| over the buildings. Written straight
// against the plugin ABI (not from a generated stub) because its number of inputs is the
// generated scenario's building count. LCM encoding of response_t: 8-byte fingerprint,
// then int64 step and three doubles, all big-endian.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "couple/builtscene_model_abi.h"

namespace {

constexpr std::size_t kSize = 8 + 8 + 3 * 8;

uint64_t load_be(const unsigned char* p) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | p[i];
  return v;
}
void store_be(unsigned char* p, uint64_t v) {
  for (int i = 7; i >= 0; --i, v >>= 8) p[i] = static_cast<unsigned char>(v & 0xff);
}
double as_double(uint64_t bits) {
  double d;
  std::memcpy(&d, &bits, sizeof d);
  return d;
}
uint64_t as_bits(double d) {
  uint64_t b;
  std::memcpy(&b, &d, sizeof b);
  return b;
}
void set_error(char* error, std::size_t size, const char* message) {
  if (size == 0) return;
  std::strncpy(error, message, size - 1);
  error[size - 1] = 0;
}

struct District {};

}  // namespace

extern "C" int builtscene_model_abi_version(void) { return BUILTSCENE_MODEL_ABI_VERSION; }

extern "C" void* builtscene_model_create(const char*, char*, size_t) { return new District{}; }

extern "C" int builtscene_model_step(void*, int64_t step, double, const bs_buffer* inputs, size_t n_inputs,
                                     bs_emit_fn emit, void* context, char* error, size_t error_size) {
  if (n_inputs == 0) {
    set_error(error, error_size, "district: no inputs");
    return 1;
  }
  double d = 0, v = 0, a = 0;
  for (std::size_t i = 0; i < n_inputs; ++i) {
    if (inputs[i].size != kSize) {
      set_error(error, error_size, "district: an input is not a wsc.response_t");
      return 1;
    }
    d += as_double(load_be(inputs[i].data + 16));
    v += as_double(load_be(inputs[i].data + 24));
    a = std::max(a, std::abs(as_double(load_be(inputs[i].data + 32))));
  }
  unsigned char out[kSize];
  std::memcpy(out, inputs[0].data, 8);  // the type's fingerprint
  store_be(out + 8, static_cast<uint64_t>(step));
  store_be(out + 16, as_bits(d / static_cast<double>(n_inputs)));
  store_be(out + 24, as_bits(v / static_cast<double>(n_inputs)));
  store_be(out + 32, as_bits(a));
  emit(context, 0, out, kSize);
  return 0;
}

extern "C" void builtscene_model_destroy(void* model) { delete static_cast<District*>(model); }
