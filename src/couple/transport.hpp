#pragma once
// Message transports. Model code and the wrapper never change between them:
//   udpm://GROUP:PORT?ttl=0   LCM UDP multicast (processes, hosts on a LAN)
//   memq://NAME               an in-process bus shared by every endpoint with the same
//                             NAME (models as threads of one process; tests)
//   nats://HOST:PORT          the mediator: a NATS server (nats_transport.hpp)
//   mediator                  a NATS server that `couple launch` starts for the run
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace builtscene::couple {

class Transport {
 public:
  using Handler = std::function<void(const std::string& channel, const uint8_t* data, std::size_t size)>;
  virtual ~Transport() = default;
  // Exact channel name; "" subscribes to every channel (recorders, spy).
  virtual void subscribe(const std::string& channel, Handler handler) = 0;
  virtual void publish(const std::string& channel, const uint8_t* data, std::size_t size) = 0;
  // Delivers pending messages to the handlers; waits at most timeout_ms for the first one.
  // Returns the number delivered (0 on timeout or interruption).
  virtual int handle(int timeout_ms) = 0;
  virtual std::string url() const = 0;
  // A descriptor that polls readable while messages wait for handle(); -1 when there is
  // none. Lets one thread block on several transports at once (hybrid_transport.hpp).
  virtual int wait_fd() const { return -1; }

  // Recovery (a mediator that keeps each channel's history, see nats_transport.hpp).
  virtual bool keeps_history() const { return false; }
  // Like subscribe(), but from the channel's first stored message, then live.
  virtual void subscribe_from_start(const std::string& channel, Handler handler) { subscribe(channel, std::move(handler)); }
  // The newest stored message of a channel; empty when none is stored.
  virtual std::vector<uint8_t> last_stored(const std::string& /*channel*/) { return {}; }
  // A restarted group of sub-models re-runs together: a step already on the mediator goes
  // again to the group's peers only (the hybrid transport's LCM); elsewhere nothing.
  virtual void publish_within_group(const std::string& /*channel*/, const uint8_t* /*data*/, std::size_t /*size*/) {}
};

// Throws InputError for an unknown scheme, Failure when the transport cannot start
// (for udpm, with the multicast-route fix in the message).
std::unique_ptr<Transport> make_transport(const std::string& url);

bool is_in_process(const std::string& url);  // memq://

inline constexpr const char* kMediator = "mediator";

}  // namespace builtscene::couple
