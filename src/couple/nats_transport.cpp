#include "couple/nats_transport.hpp"

#include <nats/nats.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>
#include <vector>

#include "core/errors.hpp"
#include "core/logging.hpp"

namespace builtscene::couple {
namespace {

std::string status_text(natsStatus s) {
  const char* last = nats_GetLastError(nullptr);
  return std::string(natsStatus_GetText(s)) + (last && *last ? std::string(": ") + last : "");
}

// A NATS subject token may not be empty or hold spaces or the wildcards * and >.
void check_channel(const std::string& url, const std::string& channel) {
  bool ok = !channel.empty() && channel.front() != '.' && channel.back() != '.' &&
            channel.find("..") == std::string::npos;
  for (char c : channel) ok = ok && c != '*' && c != '>' && c > ' ' && c != 127;
  if (!ok)
    throw InputError("transport '" + url + "': channel '" + channel +
                     "' is not a valid NATS subject (no spaces, '*', '>' or empty '.' parts)");
}

std::string stream_name(const std::string& prefix) { return "BS_" + prefix; }

constexpr int kConnectAttempts = 6;

class NatsTransport final : public Transport {
 public:
  NatsTransport(std::string url, std::string address, std::string prefix)
      : url_(std::move(url)), prefix_(std::move(prefix)) {
    wake_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (wake_ < 0) throw Failure("mediator " + url_ + ": eventfd failed");
    natsOptions* opts = nullptr;
    natsStatus s = natsOptions_Create(&opts);
    if (s == NATS_OK) s = natsOptions_SetURL(opts, address.c_str());
    // Each publish goes out at once: a coupled step waits for its inputs, so batching
    // only adds latency.
    if (s == NATS_OK) s = natsOptions_SetSendAsap(opts, true);
    if (s == NATS_OK) s = natsOptions_SetTimeout(opts, 10000);
    if (s == NATS_OK) s = natsOptions_SetMaxReconnect(opts, 20);
    if (s == NATS_OK) s = natsOptions_SetReconnectWait(opts, 250);
    // The library's shared delivery thread instead of one thread per subscription: a
    // wrapper subscribes to a few channels and statuses, a district aggregator to hundreds,
    // and a process may host many wrappers; the callback only queues for handle().
    if (s == NATS_OK) s = natsOptions_UseGlobalMessageDelivery(opts, true);
    // A hundred model processes connecting at once to a server on a loaded machine (load
    // average 150+) timed out or got no PONG in time (issue 11): try again a few times.
    // A refused connection (no server) fails at once.
    for (int attempt = 1; s == NATS_OK; ++attempt) {
      s = natsConnection_Connect(&conn_, opts);
      if (s == NATS_OK || attempt == kConnectAttempts ||
          (s != NATS_TIMEOUT && s != NATS_PROTOCOL_ERROR && s != NATS_IO_ERROR && s != NATS_STALE_CONNECTION))
        break;
      spdlog::warn("mediator {}: connecting failed ({}), attempt {} of {}; trying again", address, status_text(s), attempt,
                   kConnectAttempts);
      std::this_thread::sleep_for(std::chrono::seconds(1));
      s = NATS_OK;
    }
    natsOptions_Destroy(opts);
    if (s != NATS_OK) close(wake_);
    if (s != NATS_OK)
      throw Failure("cannot connect to the mediator (NATS server) at " + address + " (" + url_ + "): " +
                    status_text(s) +
                    ". Start one (nats-server) or let `builtscene couple launch` start it (transport: mediator)");
  }

  ~NatsTransport() override {
    for (auto& sub : subs_) natsSubscription_Unsubscribe(sub.sub);
    {
      // The library's delivery threads may be inside on_message: wait until each has
      // returned before the inbox goes away.
      std::unique_lock lock(m_);
      cv_.wait_for(lock, std::chrono::seconds(5), [&] { return completed_ == subs_.size(); });
    }
    for (auto& sub : subs_) natsSubscription_Destroy(sub.sub);
    natsConnection_FlushTimeout(conn_, 2000);  // what we published reaches the server
    if (js_) jsCtx_Destroy(js_);
    natsConnection_Destroy(conn_);
    close(wake_);
  }

  void make_history_stream(const std::vector<std::string>& channels, int64_t max_per_channel) {
    std::vector<std::string> subjects;
    for (const auto& c : channels) {
      check_channel(url_, c);
      subjects.push_back(prefix_ + "." + c);
    }
    std::vector<const char*> ptrs;
    for (const auto& s : subjects) ptrs.push_back(s.c_str());
    const std::string name = stream_name(prefix_);
    jsStreamConfig cfg;
    jsStreamConfig_Init(&cfg);
    cfg.Name = name.c_str();
    cfg.Subjects = ptrs.data();
    cfg.SubjectsLen = static_cast<int>(ptrs.size());
    cfg.MaxMsgsPerSubject = max_per_channel;
    cfg.Storage = js_FileStorage;
    jsStreamInfo* si = nullptr;
    jsErrCode jerr = static_cast<jsErrCode>(0);
    const natsStatus s = js_AddStream(&si, jetstream(), &cfg, nullptr, &jerr);
    if (si) jsStreamInfo_Destroy(si);
    if (s != NATS_OK)
      throw Failure("mediator " + url_ + ": cannot create the history stream " + name + " (is JetStream enabled?): " +
                    status_text(s));
  }

  bool keeps_history() const override { return true; }

  void subscribe_from_start(const std::string& channel, Handler handler) override {
    check_channel(url_, channel);
    const std::string subject = prefix_ + "." + channel;
    auto slot = std::make_unique<Slot>(Slot{this, subs_.size()});
    jsSubOptions so;
    jsSubOptions_Init(&so);
    so.Stream = stream_.c_str();
    so.Ordered = true;  // no acks; the library re-creates the consumer on a gap
    so.Config.DeliverPolicy = js_DeliverAll;
    natsSubscription* sub = nullptr;
    jsErrCode jerr = static_cast<jsErrCode>(0);
    natsStatus s = js_Subscribe(&sub, jetstream(), subject.c_str(), &NatsTransport::on_message, slot.get(), nullptr,
                                &so, &jerr);
    if (s == NATS_OK) s = natsSubscription_SetPendingLimits(sub, -1, -1);
    if (s == NATS_OK) s = natsSubscription_SetOnCompleteCB(sub, &NatsTransport::on_complete, this);
    if (s != NATS_OK) {
      if (sub) natsSubscription_Destroy(sub);
      throw Failure("mediator " + url_ + ": cannot replay '" + subject + "' from stream " + stream_ + ": " +
                    status_text(s));
    }
    std::lock_guard lock(m_);
    subs_.push_back({sub, std::move(handler), std::move(slot)});
  }

  std::vector<uint8_t> last_stored(const std::string& channel) override {
    check_channel(url_, channel);
    const std::string subject = prefix_ + "." + channel;
    natsMsg* msg = nullptr;
    jsErrCode jerr = static_cast<jsErrCode>(0);
    const natsStatus s = js_GetLastMsg(&msg, jetstream(), stream_.c_str(), subject.c_str(), nullptr, &jerr);
    if (s == NATS_NOT_FOUND || (s != NATS_OK && jerr == JSNoMessageFoundErr)) return {};
    if (s != NATS_OK)
      throw Failure("mediator " + url_ + ": cannot read the history of '" + channel + "': " + status_text(s));
    const auto* d = reinterpret_cast<const uint8_t*>(natsMsg_GetData(msg));
    std::vector<uint8_t> out(d, d + natsMsg_GetDataLength(msg));
    natsMsg_Destroy(msg);
    return out;
  }

  void subscribe(const std::string& channel, Handler handler) override {
    if (!channel.empty()) check_channel(url_, channel);
    const std::string subject = channel.empty() ? prefix_ + ".>" : prefix_ + "." + channel;
    auto slot = std::make_unique<Slot>(Slot{this, subs_.size()});
    natsSubscription* sub = nullptr;
    natsStatus s = natsConnection_Subscribe(&sub, conn_, subject.c_str(), &NatsTransport::on_message, slot.get());
    // The wrapper's flow control bounds what is pending; the library must not drop.
    if (s == NATS_OK) s = natsSubscription_SetPendingLimits(sub, -1, -1);
    if (s == NATS_OK) s = natsSubscription_SetOnCompleteCB(sub, &NatsTransport::on_complete, this);
    if (s != NATS_OK) {
      if (sub) natsSubscription_Destroy(sub);
      throw Failure("mediator " + url_ + ": cannot subscribe to '" + subject + "': " + status_text(s));
    }
    std::lock_guard lock(m_);
    subs_.push_back({sub, std::move(handler), std::move(slot)});
  }

  void publish(const std::string& channel, const uint8_t* data, std::size_t size) override {
    check_channel(url_, channel);
    const std::string subject = prefix_ + "." + channel;
    const natsStatus s = natsConnection_Publish(conn_, subject.c_str(), data, static_cast<int>(size));
    if (s != NATS_OK) throw Failure("mediator " + url_ + ": cannot publish on '" + channel + "': " + status_text(s));
  }

  int handle(int timeout_ms) override {
    std::deque<Item> batch;
    {
      std::unique_lock lock(m_);
      if (queue_.empty())
        cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [&] { return !queue_.empty(); });
      // Reset under the lock: the descriptor is readable exactly while the queue is not empty.
      uint64_t count;
      [[maybe_unused]] const auto got = read(wake_, &count, sizeof count);
      batch.swap(queue_);
    }
    for (const auto& item : batch) subs_[item.sub].handler(item.channel, item.data.data(), item.data.size());
    return static_cast<int>(batch.size());
  }

  std::string url() const override { return url_; }
  int wait_fd() const override { return wake_; }

 private:
  struct Slot {
    NatsTransport* self;
    std::size_t index;
  };
  struct Sub {
    natsSubscription* sub;
    Handler handler;
    std::unique_ptr<Slot> slot;
  };
  struct Item {
    std::size_t sub;
    std::string channel;
    std::vector<uint8_t> data;
  };

  // Runs on the library's delivery thread: queue for handle(), which runs the handlers
  // on the caller's thread like the other transports.
  static void on_message(natsConnection*, natsSubscription*, natsMsg* msg, void* closure) {
    auto* slot = static_cast<Slot*>(closure);
    NatsTransport* self = slot->self;
    std::string subject = natsMsg_GetSubject(msg);
    const auto* d = reinterpret_cast<const uint8_t*>(natsMsg_GetData(msg));
    Item item{slot->index, subject.substr(std::min(subject.size(), self->prefix_.size() + 1)),
              std::vector<uint8_t>(d, d + natsMsg_GetDataLength(msg))};
    natsMsg_Destroy(msg);
    std::lock_guard lock(self->m_);
    self->queue_.push_back(std::move(item));
    const uint64_t one = 1;
    [[maybe_unused]] const auto put = write(self->wake_, &one, sizeof one);
    self->cv_.notify_one();
  }
  static void on_complete(void* closure) {
    auto* self = static_cast<NatsTransport*>(closure);
    std::lock_guard lock(self->m_);
    ++self->completed_;
    self->cv_.notify_all();
  }

  jsCtx* jetstream() {
    if (!js_) {
      const natsStatus s = natsConnection_JetStream(&js_, conn_, nullptr);
      if (s != NATS_OK) throw Failure("mediator " + url_ + ": no JetStream context: " + status_text(s));
    }
    return js_;
  }

  std::string url_, prefix_, stream_ = stream_name(prefix_);
  natsConnection* conn_ = nullptr;
  jsCtx* js_ = nullptr;
  std::vector<Sub> subs_;  // added before traffic starts (the wrapper subscribes up front)
  std::mutex m_;           // guards queue_ and completed_
  std::condition_variable cv_;
  std::deque<Item> queue_;
  std::size_t completed_ = 0;
  int wake_ = -1;  // eventfd, readable while queue_ holds messages (wait_fd)
};

}  // namespace

bool is_nats_url(const std::string& url) { return url.rfind("nats://", 0) == 0; }

std::string nats_server_address(const std::string& url) {
  const auto q = url.find('?');
  return q == std::string::npos ? url : url.substr(0, q);
}

std::unique_ptr<Transport> make_nats_transport(const std::string& url) {
  const std::string address = nats_server_address(url);
  if (!is_nats_url(url) || address.size() <= 7 || address.find(':', 7) == std::string::npos)
    throw InputError("transport '" + url + "': expected nats://HOST:PORT[?prefix=P]");
  std::string prefix = "bs";
  if (const auto q = url.find('?'); q != std::string::npos) {
    const std::string query = url.substr(q + 1);
    if (query.rfind("prefix=", 0) != 0 || query.size() == 7 || query.find_first_of("&.*> ") != std::string::npos)
      throw InputError("transport '" + url + "': bad option '" + query + "' (nats://HOST:PORT?prefix=NAME)");
    prefix = query.substr(7);
  }
  return std::make_unique<NatsTransport>(url, address, prefix);
}

void create_history_stream(const std::string& url, const std::vector<std::string>& channels, int64_t max_per_channel) {
  auto t = make_nats_transport(url);
  static_cast<NatsTransport&>(*t).make_history_stream(channels, max_per_channel);
}

}  // namespace builtscene::couple
