#include "couple/transport.hpp"

#include <lcm/lcm.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <atomic>
#include <vector>

#include "core/errors.hpp"
#include "couple/nats_transport.hpp"

namespace builtscene::couple {
namespace {

// ---- memq: an in-process bus ------------------------------------------------------------

class MemqEndpoint;

class MemqBus {
 public:
  static std::shared_ptr<MemqBus> get(const std::string& name) {
    static std::mutex m;
    static std::map<std::string, std::weak_ptr<MemqBus>> buses;
    std::lock_guard lock(m);
    auto bus = buses[name].lock();
    if (!bus) {
      bus = std::make_shared<MemqBus>();
      buses[name] = bus;
    }
    return bus;
  }
  void attach(MemqEndpoint* e) {
    std::lock_guard lock(m_);
    endpoints_.push_back(e);
  }
  void detach(MemqEndpoint* e) {
    std::lock_guard lock(m_);
    std::erase(endpoints_, e);
  }
  void publish(const std::string& channel, const uint8_t* data, std::size_t size);

 private:
  std::mutex m_;  // guards endpoints_
  std::vector<MemqEndpoint*> endpoints_;
};

class MemqEndpoint final : public Transport {
 public:
  // `drop` > 0 loses that fraction of the messages delivered to this endpoint (seeded),
  // to test the wrapper's recovery from a lossy network.
  MemqEndpoint(std::string url, const std::string& name, double drop, uint64_t seed)
      : url_(std::move(url)), bus_(MemqBus::get(name)), drop_(drop), rng_(seed) {
    wake_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (wake_ < 0) throw Failure("memq: eventfd failed");
    bus_->attach(this);
  }
  ~MemqEndpoint() override {
    bus_->detach(this);
    close(wake_);
  }
  int wait_fd() const override { return wake_; }

  void subscribe(const std::string& channel, Handler handler) override {
    std::lock_guard lock(m_);
    if (channel.empty())
      all_.push_back(std::move(handler));
    else
      handlers_[channel].push_back(std::move(handler));
  }
  void publish(const std::string& channel, const uint8_t* data, std::size_t size) override {
    bus_->publish(channel, data, size);
  }
  // Called by the bus from the publisher's thread.
  void deliver(const std::string& channel, const uint8_t* data, std::size_t size) {
    std::lock_guard lock(m_);
    if (all_.empty() && !handlers_.count(channel)) return;
    if (drop_ > 0 && std::uniform_real_distribution<double>(0, 1)(rng_) < drop_) return;
    queue_.push_back({channel, std::vector<uint8_t>(data, data + size)});
    const uint64_t one = 1;
    [[maybe_unused]] const auto put = write(wake_, &one, sizeof one);
    cv_.notify_one();
  }
  int handle(int timeout_ms) override {
    std::deque<Item> batch;
    {
      std::unique_lock lock(m_);
      if (queue_.empty()) cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [&] { return !queue_.empty(); });
      // Reset under the lock: the descriptor is readable exactly while the queue is not empty.
      uint64_t count;
      [[maybe_unused]] const auto got = read(wake_, &count, sizeof count);
      batch.swap(queue_);
    }
    for (const auto& item : batch) {
      for (auto& h : all_) h(item.channel, item.data.data(), item.data.size());
      auto it = handlers_.find(item.channel);
      if (it != handlers_.end())
        for (auto& h : it->second) h(item.channel, item.data.data(), item.data.size());
    }
    return static_cast<int>(batch.size());
  }
  std::string url() const override { return url_; }

 private:
  struct Item {
    std::string channel;
    std::vector<uint8_t> data;
  };
  std::string url_;
  std::shared_ptr<MemqBus> bus_;
  double drop_;
  std::mt19937_64 rng_;
  std::mutex m_;  // guards queue_, rng_ and handler registration; handlers run outside it
  std::condition_variable cv_;
  std::deque<Item> queue_;
  std::map<std::string, std::vector<Handler>> handlers_;
  std::vector<Handler> all_;
  int wake_ = -1;  // eventfd, readable while queue_ holds messages (wait_fd)
};

void MemqBus::publish(const std::string& channel, const uint8_t* data, std::size_t size) {
  std::lock_guard lock(m_);
  for (auto* e : endpoints_) e->deliver(channel, data, size);
}

// ---- udpm: LCM ---------------------------------------------------------------------------

std::string regex_escape(const std::string& s) {
  std::string r;
  for (char c : s) {
    if (std::string(".^$|()[]{}*+?\\").find(c) != std::string::npos) r += '\\';
    r += c;
  }
  return r;
}

class LcmTransport final : public Transport {
  static constexpr int kMaxDrain = 512;

 public:
  explicit LcmTransport(std::string url) : url_(std::move(url)) {
    lcm_ = lcm_create(url_.c_str());
    if (!lcm_)
      throw Failure("cannot start LCM on '" + url_ +
                    "'. On one host LCM needs a multicast route, e.g. as root: "
                    "ip route add 224.0.0.0/4 dev lo (and ip link set lo multicast on)");
  }
  ~LcmTransport() override {
    for (auto* s : subs_) lcm_unsubscribe(lcm_, s);
    lcm_destroy(lcm_);
  }
  void subscribe(const std::string& channel, Handler handler) override {
    handlers_.push_back(std::make_unique<Handler>(
        [this, h = std::move(handler)](const std::string& c, const uint8_t* d, std::size_t n) {
          ++count_;
          h(c, d, n);
        }));
    const std::string pattern = channel.empty() ? ".*" : regex_escape(channel);
    lcm_subscription_t* s = lcm_subscribe(lcm_, pattern.c_str(), &LcmTransport::on_message, handlers_.back().get());
    if (!s) throw Failure("LCM: cannot subscribe to channel '" + channel + "'");
    // The default queue (30 messages) drops the newest when a model falls behind; the
    // wrapper's flow control bounds the backlog, so no limit is needed here.
    lcm_subscription_set_queue_capacity(s, 0);
    subs_.push_back(s);
  }
  void publish(const std::string& channel, const uint8_t* data, std::size_t size) override {
    if (lcm_publish(lcm_, channel.c_str(), data, static_cast<unsigned int>(size)) != 0)
      throw Failure("LCM: cannot publish on channel '" + channel + "' (" + url_ + ")");
  }
  int handle(int timeout_ms) override {
    count_ = 0;
    pollfd p{lcm_get_fileno(lcm_), POLLIN, 0};
    int wait = timeout_ms;
    // Drain what is already there, then return; at most kMaxDrain datagrams, so that a
    // wrapper on a busy group (every socket of the group receives every datagram) gets back
    // to its own loop: unbounded, it could stay here as long as traffic flowed.
    for (int k = 0; k < kMaxDrain && poll(&p, 1, wait) > 0 && (p.revents & POLLIN); ++k) {
      if (lcm_handle(lcm_) != 0) break;
      wait = 0;
    }
    return count_;
  }
  std::string url() const override { return url_; }
  int wait_fd() const override { return lcm_get_fileno(lcm_); }

 private:
  static void on_message(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
    auto* h = static_cast<Handler*>(user);
    (*h)(channel, static_cast<const uint8_t*>(rbuf->data), rbuf->data_size);
  }
  std::string url_;
  lcm_t* lcm_ = nullptr;
  std::vector<std::unique_ptr<Handler>> handlers_;
  std::vector<lcm_subscription_t*> subs_;
  int count_ = 0;
};

}  // namespace

bool is_in_process(const std::string& url) { return url.rfind("memq://", 0) == 0; }

std::unique_ptr<Transport> make_transport(const std::string& url) {
  if (is_in_process(url)) {
    // memq://NAME[?drop=FRACTION&seed=N]
    std::string name = url.substr(7), query;
    if (auto q = name.find('?'); q != std::string::npos) {
      query = name.substr(q + 1);
      name = name.substr(0, q);
    }
    double drop = 0;
    uint64_t seed = 1;
    std::stringstream qs(query);
    std::string kv;
    while (std::getline(qs, kv, '&')) {
      const auto eq = kv.find('=');
      const std::string k = kv.substr(0, eq), v = eq == std::string::npos ? "" : kv.substr(eq + 1);
      try {
        if (k == "drop") drop = std::stod(v);
        else if (k == "seed") seed = std::stoull(v);
        else throw InputError("");
      } catch (const std::exception&) {
        throw InputError("transport '" + url + "': bad option '" + kv + "' (memq://NAME?drop=FRACTION&seed=N)");
      }
    }
    static std::atomic<uint64_t> instance{0};
    return std::make_unique<MemqEndpoint>(url, name, drop, seed * 1000003 + instance++);
  }
  if (url.rfind("udpm://", 0) == 0) return std::make_unique<LcmTransport>(url);
  if (is_nats_url(url)) return make_nats_transport(url);
  if (url == kMediator)
    throw InputError("transport 'mediator' means a NATS server that `builtscene couple launch` starts; "
                     "to connect to a running one, give its nats://HOST:PORT");
  throw InputError("unknown transport '" + url + "' (use udpm://GROUP:PORT?ttl=0, nats://HOST:PORT, mediator or memq://NAME)");
}

}  // namespace builtscene::couple
