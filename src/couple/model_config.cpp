#include "couple/model_config.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "core/errors.hpp"
#include "couple/lcm_codec.hpp"
#include "couple/status.hpp"

namespace builtscene::couple {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::size_t line_of(const YAML::Node& n) { return n.Mark().line >= 0 ? static_cast<std::size_t>(n.Mark().line) + 1 : 0; }

[[noreturn]] void bad(const fs::path& file, const YAML::Node& n, const std::string& msg) {
  throw_input_error(file, line_of(n), msg);
}

YAML::Node load_yaml(const fs::path& file) {
  if (!fs::exists(file)) throw InputError(located(file, 0, "file not found"));
  try {
    YAML::Node root = YAML::LoadFile(file.string());
    if (!root.IsMap()) throw_input_error(file, 1, "expected a mapping at the top level");
    return root;
  } catch (const YAML::ParserException& e) {
    throw_input_error(file, static_cast<std::size_t>(e.mark.line + 1), "YAML syntax error: " + e.msg);
  } catch (const YAML::BadFile&) {
    throw InputError(located(file, 0, "cannot read file"));
  }
}

void check_keys(const fs::path& file, const YAML::Node& map, const std::set<std::string>& allowed,
                const std::string& where) {
  for (const auto& kv : map) {
    const auto key = kv.first.as<std::string>();
    if (!allowed.count(key)) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      bad(file, kv.first, "unknown field '" + where + key + "' (allowed: " + list + ")");
    }
  }
}

template <typename T>
T get(const fs::path& file, const YAML::Node& map, const std::string& key, const std::string& where) {
  const YAML::Node n = map[key];
  if (!n) bad(file, map, "missing field '" + where + key + "'");
  try {
    return n.as<T>();
  } catch (const YAML::Exception&) {
    bad(file, n, "field '" + where + key + "' has a bad value '" + YAML::Dump(n) + "'");
  }
}

template <typename T>
T get_or(const fs::path& file, const YAML::Node& map, const std::string& key, const std::string& where, T def) {
  if (!map[key]) return def;
  return get<T>(file, map, key, where);
}

json to_json(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Map: {
      json o = json::object();
      for (const auto& kv : n) o[kv.first.as<std::string>()] = to_json(kv.second);
      return o;
    }
    case YAML::NodeType::Sequence: {
      json a = json::array();
      for (const auto& e : n) a.push_back(to_json(e));
      return a;
    }
    case YAML::NodeType::Scalar: {
      const std::string s = n.Scalar();
      if (n.Tag() == "!") return s;  // quoted
      if (s == "true" || s == "false") return s == "true";
      try {
        std::size_t pos = 0;
        const long long i = std::stoll(s, &pos);
        if (pos == s.size()) return i;
      } catch (...) {
      }
      try {
        std::size_t pos = 0;
        const double d = std::stod(s, &pos);
        if (pos == s.size()) return d;
      } catch (...) {
      }
      return s;
    }
    default: return nullptr;
  }
}

std::vector<fs::path> message_files(const fs::path& file, const YAML::Node& root) {
  std::vector<fs::path> out;
  const YAML::Node m = root["messages"];
  if (!m) return out;
  auto add = [&](const YAML::Node& n) {
    fs::path p = n.as<std::string>();
    if (p.is_relative()) p = file.parent_path() / p;
    if (!fs::exists(p)) bad(file, n, "field 'messages': file not found: " + p.string());
    out.push_back(p.lexically_normal());
  };
  if (m.IsSequence())
    for (const auto& e : m) add(e);
  else
    add(m);
  return out;
}

int positive(const fs::path& file, const YAML::Node& map, const std::string& key, const std::string& where, int def) {
  const int v = get_or<int>(file, map, key, where, def);
  if (v < 1) bad(file, map[key], "field '" + where + key + "' must be at least 1");
  return v;
}

}  // namespace

int64_t ModelConfig::steps() const { return static_cast<int64_t>(std::llround(end_time / dt)); }

const ModelConfig& ScenarioConfig::model(const std::string& name) const {
  for (const auto& m : models)
    if (m.name == name) return m;
  throw InputError(located(file, 0, "no model named '" + name + "'"));
}

std::string ScenarioConfig::local_url(const std::string& group) const {
  const auto it = std::find(groups.begin(), groups.end(), group);
  if (it == groups.end()) throw InputError(located(file, 0, "no group named '" + group + "'"));
  const int index = static_cast<int>(it - groups.begin());
  if (local_transport.rfind("memq://", 0) == 0) {
    const auto q = local_transport.find('?');
    return q == std::string::npos ? local_transport + "-" + group
                                  : local_transport.substr(0, q) + "-" + group + local_transport.substr(q);
  }
  // udpm://GROUP:PORT[?options]
  const auto colon = local_transport.rfind(':'), q = local_transport.find('?');
  const std::string port = local_transport.substr(colon + 1, q == std::string::npos ? std::string::npos : q - colon - 1);
  return local_transport.substr(0, colon + 1) + std::to_string(std::stoi(port) + index) +
         (q == std::string::npos ? "" : local_transport.substr(q));
}

ModelConfig load_model_config(const fs::path& file) {
  const YAML::Node root = load_yaml(file);
  check_keys(file, root,
             {"name", "dt", "end_time", "lookahead", "checkpoint_every", "plugin", "command", "parameters", "messages", "subscribe",
              "publish", "transport"},
             "");
  ModelConfig m;
  m.file = file;
  m.name = get<std::string>(file, root, "name", "");
  for (char c : m.name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_'))
      bad(file, root["name"], "field 'name': '" + m.name + "' must be letters, digits and '_' (it names a C++ function)");
  if (m.name.empty() || std::isdigit(static_cast<unsigned char>(m.name[0])))
    bad(file, root["name"], "field 'name' must start with a letter");
  m.dt = get<double>(file, root, "dt", "");
  if (!(m.dt > 0)) bad(file, root["dt"], "field 'dt' must be positive");
  m.end_time = get<double>(file, root, "end_time", "");
  if (!(m.end_time > 0)) bad(file, root["end_time"], "field 'end_time' must be positive");
  if (std::abs(m.end_time / m.dt - static_cast<double>(m.steps())) > 1e-6)
    bad(file, root["end_time"], "field 'end_time' must be a whole number of time steps 'dt'");
  m.lookahead = get_or<double>(file, root, "lookahead", "", 0.0);
  if (!(m.lookahead >= 0)) bad(file, root["lookahead"], "field 'lookahead' must not be negative (seconds)");
  m.checkpoint_every = get_or<int64_t>(file, root, "checkpoint_every", "", 0);
  if (m.checkpoint_every < 0) bad(file, root["checkpoint_every"], "field 'checkpoint_every' must not be negative (steps)");
  m.plugin = get_or<std::string>(file, root, "plugin", "", "");
  if (root["command"]) {
    const YAML::Node c = root["command"];
    if (c.IsSequence())
      for (const auto& e : c) m.command.push_back(e.as<std::string>());
    else
      m.command.push_back(c.as<std::string>());
    if (m.command.empty()) bad(file, c, "field 'command' is empty");
  }
  if (root["parameters"]) m.parameters = to_json(root["parameters"]);
  if (!m.parameters.is_object()) bad(file, root["parameters"], "field 'parameters' must be a mapping");
  m.parameters["dt"] = m.dt;  // every model function gets its time step
  m.messages = message_files(file, root);
  m.transport = get_or<std::string>(file, root, "transport", "", "");

  if (const YAML::Node subs = root["subscribe"]) {
    if (!subs.IsSequence()) bad(file, subs, "field 'subscribe' must be a list");
    for (std::size_t i = 0; i < subs.size(); ++i) {
      const YAML::Node s = subs[i];
      const std::string where = "subscribe[" + std::to_string(i) + "].";
      if (!s.IsMap()) bad(file, s, "field '" + where.substr(0, where.size() - 1) + "' must be a mapping");
      check_keys(file, s, {"channel", "type", "every", "substeps", "history", "lag", "initial"}, where);
      Subscription sub;
      sub.line = line_of(s);
      sub.channel = get<std::string>(file, s, "channel", where);
      sub.type = get<std::string>(file, s, "type", where);
      sub.every = positive(file, s, "every", where, 1);
      sub.substeps = positive(file, s, "substeps", where, 1);
      if (sub.every > 1 && sub.substeps > 1) bad(file, s, "fields '" + where + "every' and 'substeps' exclude each other");
      sub.history = positive(file, s, "history", where, 1);
      sub.lag = get_or<int>(file, s, "lag", where, 0);
      if (sub.lag < 0) bad(file, s["lag"], "field '" + where + "lag' must not be negative");
      if (s["initial"]) sub.initial = to_json(s["initial"]);
      for (const auto& other : m.subscribe)
        if (other.channel == sub.channel) bad(file, s, "channel '" + sub.channel + "' subscribed twice");
      m.subscribe.push_back(sub);
    }
  }
  if (const YAML::Node pubs = root["publish"]) {
    if (!pubs.IsSequence()) bad(file, pubs, "field 'publish' must be a list");
    for (std::size_t i = 0; i < pubs.size(); ++i) {
      const YAML::Node p = pubs[i];
      const std::string where = "publish[" + std::to_string(i) + "].";
      if (!p.IsMap()) bad(file, p, "field '" + where.substr(0, where.size() - 1) + "' must be a mapping");
      check_keys(file, p, {"channel", "type", "initial", "events"}, where);
      Publication pub;
      pub.line = line_of(p);
      pub.channel = get<std::string>(file, p, "channel", where);
      pub.type = get<std::string>(file, p, "type", where);
      if (p["initial"]) pub.initial = to_json(p["initial"]);
      pub.events = get_or<bool>(file, p, "events", where, false);
      for (const auto& other : m.publish)
        if (other.channel == pub.channel) bad(file, p, "channel '" + pub.channel + "' published twice");
      m.publish.push_back(pub);
    }
  }
  if (m.publish.empty()) bad(file, root, "model '" + m.name + "' publishes nothing (field 'publish')");
  if (m.plugin.empty() == m.command.empty())
    bad(file, root, "give exactly one of 'plugin' (a shared library) or 'command' (an external program)");
  return m;
}

ScenarioConfig load_scenario(const fs::path& file_in) {
  const fs::path file = fs::absolute(file_in).lexically_normal();
  const YAML::Node root = load_yaml(file);
  check_keys(file, root, {"name", "transport", "timeout", "messages", "models", "local", "models_per_process"}, "");
  ScenarioConfig sc;
  sc.file = file;
  sc.name = get_or<std::string>(file, root, "name", "", file.stem().string());
  sc.transport = get_or<std::string>(file, root, "transport", "", sc.transport);
  sc.timeout_seconds = get_or<double>(file, root, "timeout", "", sc.timeout_seconds);
  if (!(sc.timeout_seconds > 0)) bad(file, root["timeout"], "field 'timeout' must be positive (seconds)");
  sc.models_per_process = positive(file, root, "models_per_process", "", 1);
  sc.messages = message_files(file, root);
  const YAML::Node models = root["models"];
  if (!models || !models.IsSequence() || models.size() == 0) bad(file, root, "field 'models' must be a non-empty list");
  for (std::size_t i = 0; i < models.size(); ++i) {
    const YAML::Node n = models[i];
    std::string rel, group;
    const std::string where = "models[" + std::to_string(i) + "].";
    if (n.IsScalar()) {
      rel = n.as<std::string>();
    } else if (n.IsMap() && n["config"]) {
      check_keys(file, n, {"config", "group"}, where);
      rel = get<std::string>(file, n, "config", where);
      group = get_or<std::string>(file, n, "group", where, "");
      if (n["group"] && group.empty()) bad(file, n["group"], "field '" + where + "group' must not be empty");
    } else {
      bad(file, n, "field 'models[" + std::to_string(i) + "]' must be a config file path (or {config: PATH, group: NAME})");
    }
    fs::path p = rel;
    if (p.is_relative()) p = file.parent_path() / p;
    if (!fs::exists(p)) bad(file, n, "field 'models[" + std::to_string(i) + "]': file not found: " + p.string());
    sc.models.push_back(load_model_config(p.lexically_normal()));
    sc.models.back().group = group;
  }
  if (const YAML::Node local = root["local"]) {
    if (!local.IsMap()) bad(file, local, "field 'local' must be a mapping {transport: udpm://..., channels: [...]}");
    check_keys(file, local, {"transport", "channels"}, "local.");
    sc.local_transport = get_or<std::string>(file, local, "transport", "local.", sc.local_transport);
    const bool udpm = sc.local_transport.rfind("udpm://", 0) == 0, memq = sc.local_transport.rfind("memq://", 0) == 0;
    bool port_ok = memq;
    if (udpm) {
      const auto colon = sc.local_transport.rfind(':'), q = sc.local_transport.find('?');
      const std::string port = colon > 6 ? sc.local_transport.substr(colon + 1, q == std::string::npos ? std::string::npos : q - colon - 1) : "";
      port_ok = !port.empty() && port.size() <= 5 && port.find_first_not_of("0123456789") == std::string::npos;
    }
    if (!port_ok)
      bad(file, local["transport"], "field 'local.transport': '" + sc.local_transport +
                                        "' must be udpm://GROUP:PORT[?ttl=0] (or memq://NAME)");
    const YAML::Node ch = local["channels"];
    if (!ch || !ch.IsSequence() || ch.size() == 0) bad(file, local, "field 'local.channels' must be a non-empty list of channels");
    for (std::size_t i = 0; i < ch.size(); ++i) {
      if (!ch[i].IsScalar()) bad(file, ch[i], "field 'local.channels[" + std::to_string(i) + "]' must be a channel name");
      sc.local_channels.emplace(ch[i].as<std::string>(), line_of(ch[i]));
    }
  }
  validate_scenario(sc);
  return sc;
}

void validate_scenario(ScenarioConfig& sc) {
  std::set<fs::path> parsed;
  auto parse = [&](const fs::path& p) {
    if (parsed.insert(p).second) sc.types.parse_file(p);
  };
  for (const auto& p : sc.messages) parse(p);
  for (const auto& m : sc.models) {
    for (const auto& p : m.messages) parse(p);
    if (m.messages.empty() && sc.messages.empty())
      throw InputError(located(m.file, 0, "no message definitions: give field 'messages' (a .lcm file)"));
  }
  add_builtin_types(sc.types);
  sc.types.validate();

  std::set<std::string> names;
  for (const auto& m : sc.models)
    if (!names.insert(m.name).second) throw InputError(located(m.file, 0, "two models are named '" + m.name + "'"));

  auto check_type = [&](const ModelConfig& m, std::size_t line, const std::string& type, const std::string& field) {
    const LcmStruct* s = sc.types.find(type);
    if (!s) {
      std::string known;
      for (const auto& n : sc.types.names()) known += (known.empty() ? "" : ", ") + n;
      throw_input_error(m.file, line, "field '" + field + "': unknown message type '" + type + "' (known: " + known + ")");
    }
    const LcmMember* st = s->member(kStepField);
    if (!st || st->primitive != Primitive::kInt64 || !st->dims.empty())
      throw_input_error(m.file, line, "message type '" + type + "' needs a member 'int64_t " + kStepField +
                                           ";' (the wrapper stamps it with the producer's step)");
  };
  auto check_initial = [&](const ModelConfig& m, std::size_t line, const std::string& type, json v,
                           const std::string& field) {
    LcmCodec codec(sc.types, type);
    json full = codec.zero();
    if (!v.is_object()) throw_input_error(m.file, line, "field '" + field + "' must be a mapping of member values");
    for (auto& [k, val] : v.items()) {
      if (!full.contains(k)) throw_input_error(m.file, line, "field '" + field + "': type " + type + " has no member '" + k + "'");
      full[k] = val;
    }
    try {
      codec.encode(full);
    } catch (const InputError& e) {
      throw_input_error(m.file, line, "field '" + field + "': " + e.what());
    }
  };

  struct Producer {
    const ModelConfig* model;
    const Publication* pub;
  };
  std::map<std::string, Producer> producers;
  for (const auto& m : sc.models) {
    for (std::size_t i = 0; i < m.publish.size(); ++i) {
      const auto& p = m.publish[i];
      const std::string f = "publish[" + std::to_string(i) + "]";
      check_type(m, p.line, p.type, f + ".type");
      if (p.initial) check_initial(m, p.line, p.type, *p.initial, f + ".initial");
      auto [it, fresh] = producers.emplace(p.channel, Producer{&m, &p});
      if (!fresh)
        throw_input_error(m.file, p.line, "channel '" + p.channel + "' is already published by model '" +
                                              it->second.model->name + "' (" + it->second.model->file.string() + ")");
    }
  }
  for (const auto& m : sc.models) {
    for (std::size_t i = 0; i < m.subscribe.size(); ++i) {
      const auto& s = m.subscribe[i];
      const std::string f = "subscribe[" + std::to_string(i) + "]";
      check_type(m, s.line, s.type, f + ".type");
      if (s.initial) check_initial(m, s.line, s.type, *s.initial, f + ".initial");
      auto it = producers.find(s.channel);
      if (it == producers.end())
        throw_input_error(m.file, s.line, "field '" + f + ".channel': no model publishes channel '" + s.channel + "'");
      const auto& prod = it->second;
      if (prod.pub->type != s.type)
        throw_input_error(m.file, s.line, "channel '" + s.channel + "': model '" + m.name + "' expects type '" + s.type +
                                              "' but model '" + prod.model->name + "' publishes '" + prod.pub->type +
                                              "' (" + prod.model->file.string() + ":" + std::to_string(prod.pub->line) + ")");
      if (prod.pub->events) {
        if (prod.model == &m)
          throw_input_error(m.file, s.line, "channel '" + s.channel + "': a model cannot read its own event-driven channel");
        if (s.history != 1)
          throw_input_error(m.file, s.line, "field '" + f + ".history': channel '" + s.channel +
                                                "' is event-driven (held until the next event): history must be 1");
        if (!s.initial && !prod.pub->initial)
          throw_input_error(m.file, s.line, "channel '" + s.channel + "' is event-driven: give 'initial' values for subscription '" +
                                                s.channel + "' (held until the first event) or an 'initial' publish in " +
                                                prod.model->file.string());
      }
      const double want = s.substeps > 1 ? m.dt / s.substeps : m.dt * s.every;
      if (std::abs(prod.model->dt - want) > 1e-9 * std::max(want, prod.model->dt))
        throw_input_error(m.file, s.line, "channel '" + s.channel + "': producer '" + prod.model->name + "' has dt " +
                                              std::to_string(prod.model->dt) + " but every=" + std::to_string(s.every) +
                                              ", substeps=" + std::to_string(s.substeps) + " with dt " +
                                              std::to_string(m.dt) + " needs " + std::to_string(want));
    }
  }

  // Hybrid: a local channel travels between the sub-models of its producer's group.
  sc.groups.clear();
  for (const auto& m : sc.models)
    if (!m.group.empty() && std::find(sc.groups.begin(), sc.groups.end(), m.group) == sc.groups.end())
      sc.groups.push_back(m.group);
  for (const auto& [channel, line] : sc.local_channels) {
    if (is_status_channel(channel))
      throw_input_error(sc.file, line, "field 'local.channels': the status channel always goes through the mediator");
    auto it = producers.find(channel);
    if (it == producers.end())
      throw_input_error(sc.file, line, "field 'local.channels': no model publishes channel '" + channel + "'");
    if (it->second.model->group.empty())
      throw_input_error(sc.file, line, "field 'local.channels': channel '" + channel + "' is local but its producer '" +
                                           it->second.model->name + "' is in no group (models: - {config: " +
                                           it->second.model->file.filename().string() + ", group: NAME})");
  }
  if (!sc.groups.empty() && sc.local_transport.rfind("udpm://", 0) == 0) {
    const auto colon = sc.local_transport.rfind(':');
    const int last = std::stoi(sc.local_transport.substr(colon + 1)) + static_cast<int>(sc.groups.size()) - 1;
    if (last > 65535)
      throw_input_error(sc.file, 0, "field 'local.transport': " + std::to_string(sc.groups.size()) +
                                        " groups need ports up to " + std::to_string(last) + " (above 65535)");
  }

  // Dry run of the step schedule: a model advances when every producer step it needs is
  // done or is before 0 and covered by initial data. If nobody can advance before all
  // models finish, the real run would deadlock; say who waits for what.
  std::map<std::string, int64_t> done;  // steps completed per model
  for (const auto& m : sc.models) done[m.name] = 0;
  auto blocker = [&](const ModelConfig& m, int64_t n, std::string* why) -> bool {
    for (const auto& s : m.subscribe) {
      const auto& prod = producers.at(s.channel);
      const int64_t newest = s.expected_step(n);
      const int64_t oldest = newest - (s.history - 1);
      if (oldest < 0) {
        const bool covered = s.initial || (oldest == -1 && prod.pub->initial);
        if (!covered) {
          if (why)
            *why = "model '" + m.name + "' at step " + std::to_string(n) + " needs step " + std::to_string(oldest) +
                   " of channel '" + s.channel + "', which does not exist: give 'initial' values for subscription '" +
                   s.channel + "' in " + m.file.string() + " or an 'initial' publish in " + prod.model->file.string();
          return true;
        }
      }
      if (newest >= prod.model->steps()) {
        if (why)
          *why = "model '" + m.name + "' at step " + std::to_string(n) + " needs step " + std::to_string(newest) +
                 " of channel '" + s.channel + "' but model '" + prod.model->name + "' runs only " +
                 std::to_string(prod.model->steps()) + " steps";
        return true;
      }
      if (newest >= done[prod.model->name]) {
        if (why)
          *why = "model '" + m.name + "' at step " + std::to_string(n) + " waits for channel '" + s.channel +
                 "' step " + std::to_string(newest) + " from model '" + prod.model->name + "' (at step " +
                 std::to_string(done[prod.model->name]) + ")";
        return true;
      }
    }
    return false;
  };
  while (true) {
    bool progressed = false, finished = true;
    for (const auto& m : sc.models) {
      int64_t& n = done[m.name];
      while (n < m.steps() && !blocker(m, n, nullptr)) {
        ++n;
        progressed = true;
      }
      if (n < m.steps()) finished = false;
    }
    if (finished) break;
    if (!progressed) {
      std::string why;
      for (const auto& m : sc.models)
        if (done[m.name] < m.steps() && blocker(m, done[m.name], &why)) break;
      throw InputError(located(sc.file, 0, "the coupling would deadlock: " + why +
                                               " (a cycle needs lag: 1 and initial data on one of its channels)"));
    }
  }
}

}  // namespace builtscene::couple
