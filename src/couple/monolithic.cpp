#include "couple/monolithic.hpp"

#include <set>

#include "core/errors.hpp"
#include "couple/lcm_codec.hpp"
#include "couple/model_function.hpp"

namespace builtscene::couple {

using nlohmann::json;

ChannelRecords run_monolithic(const ScenarioConfig& sc) {
  std::map<std::string, std::map<int64_t, Bytes>> data;
  std::map<std::string, std::string> channel_type;
  std::vector<std::unique_ptr<ModelFunction>> fns;
  for (const auto& m : sc.models) {
    fns.push_back(load_model_function(m, sc.types));
    for (const auto& p : m.publish) {
      channel_type[p.channel] = p.type;
      if (p.initial) {
        LcmCodec c(sc.types, p.type);
        json v = c.zero();
        for (const auto& [k, x] : p.initial->items()) v[k] = x;
        v[kStepField] = -1;
        data[p.channel][-1] = c.encode(v);
      }
    }
  }
  std::set<std::string> event_channels;
  for (const auto& m : sc.models)
    for (const auto& p : m.publish)
      if (p.events) event_channels.insert(p.channel);
  std::vector<int64_t> next(sc.models.size(), 0);
  std::map<std::string, std::size_t> producer;
  for (std::size_t i = 0; i < sc.models.size(); ++i)
    for (const auto& p : sc.models[i].publish) producer[p.channel] = i;
  std::vector<std::vector<Bytes>> sub_initial(sc.models.size());
  for (std::size_t i = 0; i < sc.models.size(); ++i)
    for (const auto& s : sc.models[i].subscribe) {
      LcmCodec c(sc.types, s.type);
      json v = c.zero();
      if (s.initial)
        for (const auto& [k, x] : s.initial->items()) v[k] = x;
      v[kStepField] = -1;
      sub_initial[i].push_back(c.encode(v));
    }
  std::vector<std::vector<const Bytes*>> args;
  std::vector<Bytes> outs;
  bool progressed = true;
  while (progressed) {
    progressed = false;
    for (std::size_t i = 0; i < sc.models.size(); ++i) {
      const auto& m = sc.models[i];
      while (next[i] < m.steps()) {
        const int64_t n = next[i];
        args.assign(m.subscribe.size(), {});
        bool ready = true;
        for (std::size_t k = 0; k < m.subscribe.size() && ready; ++k) {
          const auto& s = m.subscribe[k];
          const auto& ch = data[s.channel];
          if (event_channels.count(s.channel)) {
            // Sample-and-hold once the producer is past the step: the newest event up to it.
            const int64_t want = s.expected_step(n);
            if (want >= 0 && next[producer.at(s.channel)] <= want) {
              ready = false;
              break;
            }
            auto it = ch.upper_bound(want);
            args[k].push_back(it != ch.begin() ? &std::prev(it)->second : &sub_initial[i][k]);
            continue;
          }
          for (int h = 0; h < s.history; ++h) {
            const int64_t step = s.expected_step(n) - h;
            auto it = ch.find(step);
            if (it != ch.end())
              args[k].push_back(&it->second);
            else if (step < 0 && s.initial)
              args[k].push_back(&sub_initial[i][k]);
            else {
              ready = false;
              break;
            }
          }
        }
        if (!ready) break;
        outs.assign(m.publish.size(), {});
        fns[i]->step(n, static_cast<double>(n) * m.dt, args, outs);
        for (std::size_t k = 0; k < m.publish.size(); ++k)
          if (!(m.publish[k].events && outs[k].empty())) data[m.publish[k].channel][n] = std::move(outs[k]);
        ++next[i];
        progressed = true;
      }
    }
  }
  for (std::size_t i = 0; i < sc.models.size(); ++i)
    if (next[i] < sc.models[i].steps())
      throw Failure("monolithic run stuck: model '" + sc.models[i].name + "' at step " + std::to_string(next[i]));
  ChannelRecords out;
  for (const auto& [ch, steps] : data) {
    LcmCodec c(sc.types, channel_type[ch]);
    for (const auto& [n, b] : steps) out[ch][n] = c.decode(b);
  }
  return out;
}

}  // namespace builtscene::couple
