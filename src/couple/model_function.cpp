#include "couple/model_function.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <sstream>

#include "core/errors.hpp"
#include "couple/builtscene_model_abi.h"
#include "couple/lcm_codec.hpp"

#ifndef BUILTSCENE_COUPLE_PLUGIN_DIR
#define BUILTSCENE_COUPLE_PLUGIN_DIR ""
#endif

namespace builtscene::couple {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

class PluginModel final : public ModelFunction {
 public:
  PluginModel(const ModelConfig& cfg, const fs::path& lib) : name_(cfg.name) {
    for (const auto& p : cfg.publish) events_.push_back(p.events);  // may stay empty: no event
    handle_ = dlopen(lib.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle_) throw InputError(located(cfg.file, 0, std::string("cannot load plugin: ") + dlerror()));
    auto sym = [&](const char* s) {
      void* p = dlsym(handle_, s);
      if (!p) throw InputError(located(lib, 0, std::string("not a builtscene model plugin: missing ") + s));
      return p;
    };
    auto version = reinterpret_cast<int (*)()>(sym("builtscene_model_abi_version"));
    create_ = reinterpret_cast<decltype(create_)>(sym("builtscene_model_create"));
    step_ = reinterpret_cast<decltype(step_)>(sym("builtscene_model_step"));
    destroy_ = reinterpret_cast<decltype(destroy_)>(sym("builtscene_model_destroy"));
    if (version() != BUILTSCENE_MODEL_ABI_VERSION)
      throw InputError(located(lib, 0, "plugin ABI version " + std::to_string(version()) + ", expected " +
                                           std::to_string(BUILTSCENE_MODEL_ABI_VERSION) + ": regenerate the stub"));
    // The checkpoint hooks are optional (stubs generated before them lack them).
    auto can = reinterpret_cast<int (*)()>(dlsym(handle_, "builtscene_model_can_checkpoint"));
    save_ = reinterpret_cast<decltype(save_)>(dlsym(handle_, "builtscene_model_save"));
    load_ = reinterpret_cast<decltype(load_)>(dlsym(handle_, "builtscene_model_load"));
    checkpoints_ = can && save_ && load_ && can() != 0;
    char err[512] = "";
    model_ = create_(cfg.parameters.dump().c_str(), err, sizeof err);
    if (!model_) throw Failure("model '" + name_ + "' failed to start: " + err);
  }
  ~PluginModel() override {
    if (model_) destroy_(model_);
    // The library stays loaded: static destructors of plugins running after dlclose
    // are a classic source of crashes at exit, and a process loads each plugin once.
  }
  bool can_checkpoint() const override { return checkpoints_; }
  Bytes save() override {
    Bytes state;
    char err[512] = "";
    auto emit = [](void* c, size_t, const unsigned char* d, size_t s) { static_cast<Bytes*>(c)->assign(d, d + s); };
    if (save_(model_, emit, &state, err, sizeof err) != 0)
      throw Failure("model '" + name_ + "' could not save its checkpoint: " + err);
    return state;
  }
  void load(const Bytes& state) override {
    char err[512] = "";
    if (load_(model_, state.data(), state.size(), err, sizeof err) != 0)
      throw Failure("model '" + name_ + "' could not load its checkpoint: " + err);
  }
  void step(int64_t n, double t, const std::vector<std::vector<const Bytes*>>& inputs,
            std::vector<Bytes>& outputs) override {
    flat_.clear();
    for (const auto& sub : inputs)
      for (const Bytes* b : sub) flat_.push_back({b->data(), b->size()});
    for (auto& o : outputs) o.clear();
    char err[512] = "";
    struct Ctx {
      std::vector<Bytes>* out;
      bool bad_index = false;
    } ctx{&outputs};
    auto emit = [](void* c, size_t i, const unsigned char* d, size_t s) {
      auto* x = static_cast<Ctx*>(c);
      if (i >= x->out->size()) {
        x->bad_index = true;
        return;
      }
      (*x->out)[i].assign(d, d + s);
    };
    const int rc = step_(model_, n, t, flat_.data(), flat_.size(), emit, &ctx, err, sizeof err);
    if (rc != 0) throw Failure("model '" + name_ + "' failed at step " + std::to_string(n) + ": " + err);
    if (ctx.bad_index) throw Failure("model '" + name_ + "' emitted an output index beyond its publish list");
    for (std::size_t i = 0; i < outputs.size(); ++i)
      if (outputs[i].empty() && !events_[i])
        throw Failure("model '" + name_ + "' produced no output " + std::to_string(i) + " at step " + std::to_string(n));
  }

 private:
  std::string name_;
  std::vector<bool> events_;
  void* handle_ = nullptr;
  void* (*create_)(const char*, char*, size_t) = nullptr;
  int (*step_)(void*, int64_t, double, const bs_buffer*, size_t, bs_emit_fn, void*, char*, size_t) = nullptr;
  void (*destroy_)(void*) = nullptr;
  int (*save_)(void*, bs_emit_fn, void*, char*, size_t) = nullptr;
  int (*load_)(void*, const unsigned char*, size_t, char*, size_t) = nullptr;
  bool checkpoints_ = false;
  void* model_ = nullptr;
  std::vector<bs_buffer> flat_;
};

// JSON lines over the child's stdin/stdout:
//   -> {"init": PARAMETERS}                       <- {"ok": true[, "checkpoint": true]}
//   -> {"step": N, "t": T, "inputs": {CHANNEL: [newest, ...]}}
//   <- {"outputs": {CHANNEL: {member: value, ...}}}   or {"error": "message"}
// and, for a program that said "checkpoint": true, the checkpoint hooks:
//   -> {"save": true}                             <- {"state": ANY JSON VALUE}
//   -> {"load": THAT VALUE}                       <- {"ok": true}
class ExternalModel final : public ModelFunction {
 public:
  ExternalModel(const ModelConfig& cfg, const TypeRegistry& types) : cfg_(cfg) {
    for (const auto& s : cfg.subscribe) in_codecs_.emplace_back(types, s.type);
    for (const auto& p : cfg.publish) out_codecs_.emplace_back(types, p.type);
    int to_child[2], from_child[2];
    if (pipe2(to_child, O_CLOEXEC) != 0 || pipe2(from_child, O_CLOEXEC) != 0) throw Failure("pipe failed");
    pid_ = fork();
    if (pid_ == 0) {
      prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlive the wrapper, even when it is killed
      dup2(to_child[0], 0);
      dup2(from_child[1], 1);
      const fs::path dir = cfg.file.parent_path();
      if (!dir.empty() && chdir(dir.c_str()) != 0) _exit(127);
      std::vector<char*> argv;
      for (const auto& a : cfg.command) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      execvp(argv[0], argv.data());
      std::fprintf(stderr, "cannot run '%s': %s\n", argv[0], std::strerror(errno));
      _exit(127);
    }
    close(to_child[0]);
    close(from_child[1]);
    to_ = fdopen(to_child[1], "w");
    from_ = fdopen(from_child[0], "r");
    const json reply = call({{"init", cfg.parameters}}, -1);
    if (!reply.value("ok", false)) throw Failure("model '" + cfg.name + "' did not start: " + reply.dump());
    checkpoints_ = reply.value("checkpoint", false);
  }
  bool can_checkpoint() const override { return checkpoints_; }
  Bytes save() override {
    const json reply = call({{"save", true}}, -2);
    if (!reply.contains("state"))
      throw Failure("model '" + cfg_.name + "' could not save its checkpoint: " +
                    (reply.contains("error") ? reply["error"].dump() : "no 'state' in its reply " + reply.dump().substr(0, 200)));
    const std::string text = reply["state"].dump();
    return Bytes(text.begin(), text.end());
  }
  void load(const Bytes& state) override {
    json value;
    try {
      value = json::parse(state.begin(), state.end());
    } catch (const json::exception& e) {
      throw Failure("model '" + cfg_.name + "': its checkpoint is not JSON: " + e.what());
    }
    const json reply = call({{"load", std::move(value)}}, -2);
    if (!reply.value("ok", false))
      throw Failure("model '" + cfg_.name + "' could not load its checkpoint: " + reply.dump().substr(0, 200));
  }
  ~ExternalModel() override {
    if (to_) std::fclose(to_);
    if (from_) std::fclose(from_);
    if (pid_ > 0) {
      int status = 0;
      for (int i = 0; i < 100 && waitpid(pid_, &status, WNOHANG) == 0; ++i) usleep(10000);
      if (waitpid(pid_, &status, WNOHANG) == 0) {
        kill(pid_, SIGKILL);
        waitpid(pid_, &status, 0);
      }
    }
  }
  void step(int64_t n, double t, const std::vector<std::vector<const Bytes*>>& inputs,
            std::vector<Bytes>& outputs) override {
    json req = {{"step", n}, {"t", t}, {"inputs", json::object()}};
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      json list = json::array();
      for (const Bytes* b : inputs[i]) list.push_back(in_codecs_[i].decode(*b));
      req["inputs"][cfg_.subscribe[i].channel] = std::move(list);
    }
    const json reply = call(req, n);
    if (reply.contains("error"))
      throw Failure("model '" + cfg_.name + "' failed at step " + std::to_string(n) + ": " + reply["error"].dump());
    for (std::size_t i = 0; i < outputs.size(); ++i) {
      const auto& ch = cfg_.publish[i].channel;
      outputs[i].clear();
      // An event-driven channel without an entry (or null) has no event at this step.
      if (cfg_.publish[i].events && (!reply.contains("outputs") || !reply["outputs"].contains(ch) || reply["outputs"][ch].is_null()))
        continue;
      if (!reply.contains("outputs") || !reply["outputs"].contains(ch))
        throw Failure("model '" + cfg_.name + "' returned no output for channel '" + ch + "' at step " + std::to_string(n));
      json v = reply["outputs"][ch];
      v[kStepField] = n;
      try {
        out_codecs_[i].encode(v, outputs[i]);
      } catch (const InputError& e) {
        throw Failure("model '" + cfg_.name + "' output on '" + ch + "': " + e.what());
      }
    }
  }

 private:
  [[noreturn]] void exited(int64_t n) {
    int status = 0;
    std::string how = "exited";
    for (int i = 0; i < 200; ++i) {
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        how = WIFEXITED(status) ? "exited with code " + std::to_string(WEXITSTATUS(status))
                                : std::string("was killed by signal ") + strsignal(WTERMSIG(status));
        break;
      }
      usleep(5000);
    }
    throw Failure("model '" + cfg_.name + "' (external program " + cfg_.command[0] + ") " + how +
                  (n == -1   ? std::string(" while starting")
                   : n == -2 ? std::string(" while saving or loading its checkpoint")
                             : " at step " + std::to_string(n)));
  }
  json call(const json& req, int64_t n) {
    const std::string line = req.dump() + "\n";
    if (std::fwrite(line.data(), 1, line.size(), to_) != line.size() || std::fflush(to_) != 0) exited(n);
    std::string reply;
    int c;
    while ((c = std::fgetc(from_)) != EOF && c != '\n') reply.push_back(static_cast<char>(c));
    if (c == EOF && reply.empty()) exited(n);
    try {
      return json::parse(reply);
    } catch (const json::exception&) {
      throw Failure("model '" + cfg_.name + "' wrote a line that is not JSON: " + reply.substr(0, 200));
    }
  }
  ModelConfig cfg_;
  bool checkpoints_ = false;
  std::vector<LcmCodec> in_codecs_, out_codecs_;
  pid_t pid_ = -1;
  FILE* to_ = nullptr;
  FILE* from_ = nullptr;
};

}  // namespace

fs::path find_plugin(const ModelConfig& cfg) {
  std::vector<fs::path> dirs = {fs::path(), cfg.file.parent_path()};
  if (const char* env = std::getenv("BUILTSCENE_PLUGIN_PATH")) {
    std::stringstream ss(env);
    std::string d;
    while (std::getline(ss, d, ':'))
      if (!d.empty()) dirs.emplace_back(d);
  }
  if (std::strlen(BUILTSCENE_COUPLE_PLUGIN_DIR) > 0) dirs.emplace_back(BUILTSCENE_COUPLE_PLUGIN_DIR);
  const fs::path p = cfg.plugin;
  std::vector<fs::path> names = {p};
  if (p.extension() != ".so") {
    names.push_back(p.parent_path() / ("lib" + p.filename().string() + ".so"));
    names.push_back(p.parent_path() / (p.filename().string() + ".so"));
  }
  std::string tried;
  for (const auto& d : dirs) {
    if (p.is_absolute() && !d.empty()) continue;
    for (const auto& n : names) {
      const fs::path c = d.empty() ? n : d / n;
      if (fs::is_regular_file(c)) return fs::absolute(c);
      tried += " " + c.string();
    }
  }
  throw InputError(located(cfg.file, 0, "field 'plugin': '" + cfg.plugin + "' not found (tried:" + tried +
                                            "); build the model's stub (cmake) or set BUILTSCENE_PLUGIN_PATH"));
}

std::unique_ptr<ModelFunction> load_model_function(const ModelConfig& cfg, const TypeRegistry& types) {
  if (!cfg.command.empty()) return std::make_unique<ExternalModel>(cfg, types);
  return std::make_unique<PluginModel>(cfg, find_plugin(cfg));
}

}  // namespace builtscene::couple
