#include "couple/nats_server.hpp"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "core/errors.hpp"

namespace builtscene::couple {
namespace fs = std::filesystem;

namespace {
std::string tail(const fs::path& file, std::size_t n = 400) {
  std::ifstream f(file);
  std::stringstream ss;
  ss << f.rdbuf();
  std::string s = ss.str();
  if (s.size() > n) s = "..." + s.substr(s.size() - n);
  for (char& c : s)
    if (c == '\n') c = ' ';
  return s;
}
}  // namespace

NatsServer::NatsServer(const std::string& bind, double timeout_s) {
  std::string templ = (fs::temp_directory_path() / "builtscene-mediator-XXXXXX").string();
  if (!mkdtemp(templ.data())) throw Failure("mediator: cannot create a temporary folder in " + fs::temp_directory_path().string());
  dir_ = templ;
  const std::string store = (dir_ / "jetstream").string(), log = (dir_ / "nats-server.log").string();
  const pid_t parent = getpid();
  pid_ = fork();
  if (pid_ < 0) {
    fs::remove_all(dir_);
    throw Failure("mediator: fork failed");
  }
  if (pid_ == 0) {
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(1);  // the launcher died before prctl
    // -p -1: the server picks a free port and writes it to the ports file.
    execlp("nats-server", "nats-server", "-a", bind.c_str(), "-p", "-1", "-js", "-sd", store.c_str(),
           "--ports_file_dir", dir_.c_str(), "-l", log.c_str(), static_cast<char*>(nullptr));
    std::fprintf(stderr, "cannot run nats-server: %s\n", std::strerror(errno));
    _exit(127);
  }
  const fs::path ports = dir_ / ("nats-server_" + std::to_string(pid_) + ".ports");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (url_.empty()) {
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      const std::string why = tail(log);
      fs::remove_all(dir_);
      throw Failure(WIFEXITED(status) && WEXITSTATUS(status) == 127
                        ? "mediator: nats-server is not installed (Debian package nats-server; bash scripts/setup)"
                        : "mediator: nats-server exited at start: " + why);
    }
    if (std::chrono::steady_clock::now() > deadline) {
      stop();
      throw Failure("mediator: nats-server did not report its port within " + std::to_string(timeout_s) + " s");
    }
    if (fs::exists(ports)) {
      try {
        const auto j = nlohmann::json::parse(std::ifstream(ports));
        url_ = j.at("nats").at(0).get<std::string>();
      } catch (const std::exception&) {
        // written but not complete yet
      }
    }
    if (url_.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

double NatsServer::cpu_seconds() const {
  if (pid_ <= 0) return 0;
  std::ifstream f("/proc/" + std::to_string(pid_) + "/stat");
  std::string s((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const auto close = s.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream rest(s.substr(close + 2));
  std::string field;
  double utime = 0, stime = 0;
  // Fields after the command: state(3) ... utime(14) stime(15).
  for (int i = 3; i <= 15 && rest >> field; ++i) {
    if (i == 14) utime = std::stod(field);
    if (i == 15) stime = std::stod(field);
  }
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

void NatsServer::stop() {
  if (pid_ > 0) {
    kill(pid_, SIGTERM);
    int status = 0;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (waitpid(pid_, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        kill(pid_, SIGKILL);
        waitpid(pid_, &status, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    pid_ = -1;
  }
  if (!dir_.empty()) {
    std::error_code ec;
    fs::remove_all(dir_, ec);
    dir_.clear();
  }
}

NatsServer::~NatsServer() { stop(); }

}  // namespace builtscene::couple
