// Raw LCM ping-pong over udpm (no wrapper, no codec): the floor for the coupling loop's
// cost per message. An echo thread with its own LCM instance answers every PING with a
// PONG; one iteration is one round trip (two messages through the kernel's multicast
// loopback). bench/couple_steps.sh runs it next to the coupled example, in the same
// network namespace. Also: our runtime codec's cost per message.
#include <benchmark/benchmark.h>
#include <lcm/lcm.h>
#include <poll.h>

#include <atomic>
#include <cstdlib>
#include <string>
#include <thread>

#include "couple/lcm_codec.hpp"
#include "couple/lcm_types.hpp"

namespace {

std::string url() {
  const char* u = std::getenv("BUILTSCENE_LCM_URL");
  return u ? u : "udpm://239.255.76.67:7667?ttl=0";
}

void BM_LcmUdpmPingPong(benchmark::State& state) {
  lcm_t* a = lcm_create(url().c_str());
  lcm_t* b = lcm_create(url().c_str());
  if (!a || !b) {
    state.SkipWithError("LCM udpm unavailable (no multicast route? see docs/coupling.md)");
    return;
  }
  std::atomic<bool> stop{false};
  static std::atomic<int> pongs{0};
  pongs = 0;
  lcm_subscribe(b, "BENCH_PING", [](const lcm_recv_buf_t* rb, const char*, void* u) {
    lcm_publish(static_cast<lcm_t*>(u), "BENCH_PONG", rb->data, rb->data_size);
  }, b);
  lcm_subscribe(a, "BENCH_PONG", [](const lcm_recv_buf_t*, const char*, void*) { ++pongs; }, nullptr);
  std::thread echo([&] {
    pollfd p{lcm_get_fileno(b), POLLIN, 0};
    while (!stop)
      if (poll(&p, 1, 50) > 0) lcm_handle(b);
  });
  unsigned char msg[48] = {};  // about the size of the example's messages
  pollfd p{lcm_get_fileno(a), POLLIN, 0};
  for (auto _ : state) {
    const int want = pongs + 1;
    lcm_publish(a, "BENCH_PING", msg, sizeof msg);
    while (pongs < want) {
      if (poll(&p, 1, 1000) <= 0) {
        state.SkipWithError("a PONG was lost");
        break;
      }
      lcm_handle(a);
    }
  }
  stop = true;
  echo.join();
  lcm_destroy(a);
  lcm_destroy(b);
  state.counters["messages_per_s"] = benchmark::Counter(2.0 * static_cast<double>(state.iterations()),
                                                        benchmark::Counter::kIsRate);
}
BENCHMARK(BM_LcmUdpmPingPong)->UseRealTime()->MinTime(2.0);

void BM_CodecEncodeDecode(benchmark::State& state) {
  builtscene::couple::TypeRegistry t;
  t.parse_file(std::string(BUILTSCENE_SOURCE_DIR) + "/examples/coupling/wind-structure-control/messages.lcm");
  builtscene::couple::LcmCodec c(t, "wsc.response_t");
  const nlohmann::json v = {{"step", 12}, {"D", 0.1}, {"V", -0.2}, {"A", 1.25}};
  std::vector<uint8_t> buf;
  for (auto _ : state) {
    c.encode(v, buf);
    benchmark::DoNotOptimize(c.decode(buf));
  }
}
BENCHMARK(BM_CodecEncodeDecode);

}  // namespace
