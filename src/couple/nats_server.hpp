#pragma once
// A nats-server process started for one run (the mediator): loopback only, a free port
// chosen by the server itself, JetStream on with its storage in a private temporary
// folder. Stopped (and the folder removed) when the object goes away, whatever the
// reason (normal end, failure, Ctrl-C); it also dies with the launcher (PDEATHSIG), and
// sits in its own process group so a terminal's Ctrl-C reaches only the launcher, which
// stops the models first and the server last.
#include <sys/types.h>

#include <filesystem>
#include <string>

namespace builtscene::couple {

class NatsServer {
 public:
  // Throws Failure when nats-server is missing or does not come up within `timeout_s`.
  explicit NatsServer(const std::string& bind = "127.0.0.1", double timeout_s = 15);
  ~NatsServer();
  NatsServer(const NatsServer&) = delete;
  NatsServer& operator=(const NatsServer&) = delete;

  const std::string& url() const { return url_; }  // nats://127.0.0.1:PORT
  pid_t pid() const { return pid_; }
  // CPU time (user + system) the server has used so far, from /proc.
  double cpu_seconds() const;
  void stop();

 private:
  std::filesystem::path dir_;
  std::string url_;
  pid_t pid_ = -1;
};

}  // namespace builtscene::couple
