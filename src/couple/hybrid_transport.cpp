#include "couple/hybrid_transport.hpp"

#include <poll.h>

#include <set>

#include "core/errors.hpp"

namespace builtscene::couple {
namespace {

const ModelConfig* producer_of(const ScenarioConfig& sc, const std::string& channel) {
  for (const auto& m : sc.models)
    for (const auto& p : m.publish)
      if (p.channel == channel) return &m;
  return nullptr;
}

class HybridTransport final : public Transport {
 public:
  HybridTransport(std::unique_ptr<Transport> mediator, std::unique_ptr<Transport> local, std::set<std::string> publish_local,
                  std::set<std::string> publish_both, std::set<std::string> receive_local)
      : mediator_(std::move(mediator)),
        local_(std::move(local)),
        publish_local_(std::move(publish_local)),
        publish_both_(std::move(publish_both)),
        receive_local_(std::move(receive_local)) {}

  void subscribe(const std::string& channel, Handler handler) override {
    if (receive_local_.count(channel))
      local_->subscribe(channel, std::move(handler));
    else
      mediator_->subscribe(channel, std::move(handler));
  }
  void publish(const std::string& channel, const uint8_t* data, std::size_t size) override {
    // The mediator's copy first: a consumer outside the group then never sees a step's
    // effect before the step itself reached the server.
    if (!publish_local_.count(channel) || publish_both_.count(channel)) mediator_->publish(channel, data, size);
    if (publish_local_.count(channel)) local_->publish(channel, data, size);
  }
  int handle(int timeout_ms) override {
    int n = local_->handle(0) + mediator_->handle(0);
    if (n > 0 || timeout_ms <= 0) return n;
    pollfd fds[2] = {{local_->wait_fd(), POLLIN, 0}, {mediator_->wait_fd(), POLLIN, 0}};
    if (fds[0].fd < 0 || fds[1].fd < 0) {
      // A transport without a descriptor: wait on the mediator, look at LCM after.
      n = mediator_->handle(timeout_ms);
      return n + local_->handle(0);
    }
    if (poll(fds, 2, timeout_ms) <= 0) return 0;
    return local_->handle(0) + mediator_->handle(0);
  }
  std::string url() const override { return mediator_->url() + " + " + local_->url(); }

  bool keeps_history() const override { return mediator_->keeps_history(); }
  void subscribe_from_start(const std::string& channel, Handler handler) override {
    // LCM keeps no history: the launcher restarts the whole group, whose producers re-run
    // from their start and re-send the local steps (publish_within_group).
    if (receive_local_.count(channel))
      local_->subscribe(channel, std::move(handler));
    else
      mediator_->subscribe_from_start(channel, std::move(handler));
  }
  void publish_within_group(const std::string& channel, const uint8_t* data, std::size_t size) override {
    if (publish_local_.count(channel)) local_->publish(channel, data, size);
  }
  std::vector<uint8_t> last_stored(const std::string& channel) override { return mediator_->last_stored(channel); }

 private:
  std::unique_ptr<Transport> mediator_, local_;
  std::set<std::string> publish_local_;  // our outputs that go over LCM
  std::set<std::string> publish_both_;   // ... and to the mediator as well (bridged)
  std::set<std::string> receive_local_;  // our inputs that arrive over LCM
};

}  // namespace

bool reads_locally(const ScenarioConfig& sc, const std::string& model, const std::string& channel) {
  if (!sc.is_local(channel)) return false;
  const ModelConfig* p = producer_of(sc, channel);
  const ModelConfig& m = sc.model(model);
  return p && p->name != m.name && !m.group.empty() && p->group == m.group;
}

bool is_bridged(const ScenarioConfig& sc, const std::string& channel, bool recorder) {
  if (!sc.is_local(channel)) return false;
  if (recorder) return true;
  const ModelConfig* p = producer_of(sc, channel);
  for (const auto& m : sc.models)
    for (const auto& s : m.subscribe)
      if (s.channel == channel && m.name != p->name && m.group != p->group) return true;
  return false;
}

std::unique_ptr<Transport> make_model_transport(const ScenarioConfig& sc, const std::string& model,
                                                const std::string& url, bool recorder) {
  const ModelConfig& m = sc.model(model);
  std::set<std::string> publish_local, publish_both, receive_local;
  for (const auto& p : m.publish)
    if (sc.is_local(p.channel)) {
      publish_local.insert(p.channel);
      if (is_bridged(sc, p.channel, recorder)) publish_both.insert(p.channel);
    }
  for (const auto& s : m.subscribe)
    if (reads_locally(sc, model, s.channel)) receive_local.insert(s.channel);
  auto mediator = make_transport(url);
  if (publish_local.empty() && receive_local.empty()) return mediator;
  return std::make_unique<HybridTransport>(std::move(mediator), make_transport(sc.local_url(m.group)),
                                           std::move(publish_local), std::move(publish_both), std::move(receive_local));
}

}  // namespace builtscene::couple
