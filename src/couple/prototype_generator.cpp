#include "couple/prototype_generator.hpp"

#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/errors.hpp"
#include "couple/lcm_types.hpp"

namespace builtscene::couple {
namespace {

namespace fs = std::filesystem;

const char* kAbiHeader =
#include "couple/builtscene_model_abi.inc"
    ;

std::string cpp_type(const std::string& lcm) {
  std::string r;
  for (char c : lcm) r += c == '.' ? std::string("::") : std::string(1, c);
  return r;
}
std::string header_of(const std::string& lcm) {
  std::string r;
  for (char c : lcm) r += c == '.' ? '/' : c;
  return r + ".hpp";
}
std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}
std::string camel(const std::string& s) {
  std::string r;
  bool up = true;
  for (char c : s) {
    if (c == '_') {
      up = true;
      continue;
    }
    r += up ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
    up = false;
  }
  return r;
}

void write_file(const fs::path& p, const std::string& text, GeneratedStub& out) {
  std::ofstream f(p);
  f << text;
  if (!f) throw Failure(located(p, 0, "cannot write"));
  out.written.push_back(p);
}

struct Arg {
  std::string decl;      // in the prototype
  std::string pass;      // in the glue's call
  std::string name;
  std::string py;        // python access expression
};

}  // namespace

GeneratedStub generate_model_stub(const ModelConfig& cfg, std::vector<fs::path> messages, const fs::path& out_dir,
                                  bool overwrite) {
  if (messages.empty()) messages = cfg.messages;
  if (messages.empty()) throw InputError(located(cfg.file, 0, "no message definitions: give --messages FILE.lcm"));
  TypeRegistry types;
  for (const auto& m : messages) types.parse_file(m);
  types.validate();
  auto check = [&](const std::string& type, std::size_t line, const std::string& field) {
    const LcmStruct* s = types.find(type);
    if (!s) throw_input_error(cfg.file, line, "field '" + field + "': unknown message type '" + type + "'");
    const LcmMember* st = s->member(kStepField);
    if (!st || st->primitive != Primitive::kInt64 || !st->dims.empty())
      throw_input_error(cfg.file, line, "message type '" + type + "' needs a member 'int64_t step;'");
    return s;
  };

  // Variable names: the member name where it is unambiguous; otherwise inputs are
  // CHANNEL_member (e.g. a model's own previous output) and outputs out_CHANNEL_member.
  std::map<std::string, int> in_uses, out_uses;
  for (const auto& s : cfg.subscribe)
    if (s.history == 1)
      for (const auto& m : check(s.type, s.line, "subscribe.type")->members) ++in_uses[m.name];
  for (const auto& p : cfg.publish)
    for (const auto& m : check(p.type, p.line, "publish.type")->members) ++out_uses[m.name];
  const std::set<std::string> reserved = {"state", "step", "t", "parameters"};
  auto in_var = [&](const std::string& channel, const std::string& member) {
    return in_uses[member] > 1 || out_uses[member] > 0 || reserved.count(member) ? lower(channel) + "_" + member
                                                                                  : member;
  };
  auto out_var = [&](const std::string& channel, const std::string& member) {
    return out_uses[member] > 1 || reserved.count(member) ? "out_" + lower(channel) + "_" + member : member;
  };

  const std::string N = cfg.name;
  const std::string State = camel(N) + "State";
  std::vector<Arg> ins, outs;
  std::set<std::string> headers;
  std::ostringstream glue_in, glue_out, py_in, py_out;
  std::size_t index = 0;
  for (std::size_t i = 0; i < cfg.subscribe.size(); ++i) {
    const auto& s = cfg.subscribe[i];
    const LcmStruct* st = types.find(s.type);
    headers.insert(header_of(s.type));
    const std::string T = cpp_type(s.type);
    if (s.history == 1) {
      glue_in << "    " << T << " in" << i << ";\n    decode_input(inputs[" << index << "], in" << i << ", \""
              << s.channel << "\");\n";
      for (const auto& m : st->members) {
        if (m.name == kStepField) continue;
        const std::string v = in_var(s.channel, m.name);
        ins.push_back({"const decltype(" + T + "::" + m.name + ")& " + v, "in" + std::to_string(i) + "." + m.name, v,
                       "inputs[\"" + s.channel + "\"][0][\"" + m.name + "\"]"});
      }
      ++index;
    } else {
      const std::string v = lower(s.channel) + "_history";
      glue_in << "    std::vector<" << T << "> in" << i << "(" << s.history << ");\n    for (std::size_t k = 0; k < "
              << s.history << "; ++k) decode_input(inputs[" << index << " + k], in" << i << "[k], \"" << s.channel
              << "\");\n";
      ins.push_back({"const std::vector<" + T + ">& " + v, "in" + std::to_string(i), v,
                     "inputs[\"" + s.channel + "\"]"});
      index += static_cast<std::size_t>(s.history);
    }
  }
  for (std::size_t i = 0; i < cfg.publish.size(); ++i) {
    const auto& p = cfg.publish[i];
    const LcmStruct* st = types.find(p.type);
    headers.insert(header_of(p.type));
    const std::string T = cpp_type(p.type);
    glue_out << "    " << T << " out" << i << "{};\n";
    py_out << "        \"" << p.channel << "\": {";
    bool first = true;
    for (const auto& m : st->members) {
      if (m.name == kStepField) continue;
      const std::string v = out_var(p.channel, m.name);
      outs.push_back({"decltype(" + T + "::" + m.name + ")& " + v, "out" + std::to_string(i) + "." + m.name, v, ""});
      py_out << (first ? "" : ", ") << "\"" << m.name << "\": " << v;
      first = false;
    }
    py_out << "},\n";
  }
  const std::size_t n_inputs = index;

  std::ostringstream sig;
  sig << "void " << N << "(" << State << "& state, int64_t step, double t";
  for (const auto& a : ins) sig << ",\n    " << a.decl;
  for (const auto& a : outs) sig << ",\n    " << a.decl;
  sig << ")";

  GeneratedStub out;
  out.signature = sig.str();
  fs::create_directories(out_dir / "messages");
  for (const auto& m : messages) {
    fs::copy_file(m, out_dir / "messages" / m.filename(), fs::copy_options::overwrite_existing);
    out.written.push_back(out_dir / "messages" / m.filename());
  }
  write_file(out_dir / "builtscene_model_abi.h", kAbiHeader, out);

  std::ostringstream hpp;
  hpp << "// Generated by `builtscene couple new-model` from " << cfg.file.filename().string()
      << ". Do not edit: regenerate.\n"
      << "// The model function of '" << N << "': every input-message variable is an argument, every\n"
      << "// output-message variable a result (a reference to assign). The wrapper calls it once per\n"
      << "// time step `step` (time t = step * " << cfg.dt << ") when all inputs of the step are there.\n"
      << "#pragma once\n#include <cstdint>\n#include <string>\n#include <vector>\n#include <nlohmann/json.hpp>\n\n";
  for (const auto& h : headers) hpp << "#include \"" << h << "\"\n";
  hpp << "\n// Your model's state (defined in " << N << ".cpp); made once from the config's parameters.\n"
      << "struct " << State << ";\n"
      << State << "* " << N << "_init(const nlohmann::json& parameters);\n"
      << "void " << N << "_free(" << State << "* state);\n\n"
      << sig.str() << ";\n\n"
      << "// Optional checkpoint hooks. Define both in " << N << ".cpp and set `checkpoint_every: STEPS`\n"
      << "// in the config: a restarted model then resumes from its last checkpoint instead of\n"
      << "// replaying its inputs from step 0. save writes everything the state keeps between steps\n"
      << "// into `bytes`, load restores it; return false on error. (Weak: a model without them builds.)\n"
      << "__attribute__((weak)) bool " << N << "_save(const " << State << "& state, std::string& bytes);\n"
      << "__attribute__((weak)) bool " << N << "_load(" << State << "& state, const std::string& bytes);\n";
  write_file(out_dir / (N + "_model.hpp"), hpp.str(), out);

  std::ostringstream glue;
  glue << "// Generated by `builtscene couple new-model`. Do not edit: regenerate.\n"
       << "// The plugin interface (builtscene_model_abi.h) around " << N << "(): decodes the inputs with\n"
       << "// lcm-gen's types, calls the model function, encodes and emits the outputs.\n"
       << "#include <cstring>\n#include <exception>\n#include <stdexcept>\n#include <string>\n#include <vector>\n\n"
       << "#include \"builtscene_model_abi.h\"\n#include \"" << N << "_model.hpp\"\n\nnamespace {\n\n"
       << "template <typename T>\nvoid decode_input(const bs_buffer& b, T& msg, const char* channel) {\n"
       << "  if (msg.decode(b.data, 0, static_cast<int>(b.size)) != static_cast<int>(b.size))\n"
       << "    throw std::runtime_error(std::string(\"cannot decode the message on channel \") + channel);\n}\n\n"
       << "template <typename T>\nvoid emit_output(T& msg, int64_t step, size_t index, bs_emit_fn emit, void* context) {\n"
       << "  msg.step = step;\n  std::vector<unsigned char> buf(static_cast<size_t>(msg.getEncodedSize()));\n"
       << "  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));\n  emit(context, index, buf.data(), buf.size());\n}\n\n"
       << "void set_error(char* error, size_t size, const char* message) {\n"
       << "  if (size == 0) return;\n  std::strncpy(error, message, size - 1);\n  error[size - 1] = 0;\n}\n\n"
       << "}  // namespace\n\n"
       << "extern \"C\" int builtscene_model_abi_version(void) { return BUILTSCENE_MODEL_ABI_VERSION; }\n\n"
       << "extern \"C\" void* builtscene_model_create(const char* parameters_json, char* error, size_t error_size) {\n"
       << "  try {\n    return " << N << "_init(nlohmann::json::parse(parameters_json));\n"
       << "  } catch (const std::exception& e) {\n    set_error(error, error_size, e.what());\n  } catch (...) {\n"
       << "    set_error(error, error_size, \"unknown exception\");\n  }\n  return nullptr;\n}\n\n"
       << "extern \"C\" int builtscene_model_step(void* model, int64_t step, double t, const bs_buffer* inputs,\n"
       << "                                      size_t n_inputs, bs_emit_fn emit, void* context, char* error,\n"
       << "                                      size_t error_size) {\n  try {\n"
       << "    if (n_inputs != " << n_inputs << ") throw std::runtime_error(\"expected " << n_inputs
       << " input messages\");\n"
       << (n_inputs == 0 ? "    (void)inputs;\n" : "") << glue_in.str() << glue_out.str() << "    " << N
       << "(*static_cast<" << State << "*>(model), step, t";
  for (const auto& a : ins) glue << ", " << a.pass;
  for (const auto& a : outs) glue << ", " << a.pass;
  glue << ");\n";
  for (std::size_t i = 0; i < cfg.publish.size(); ++i)
    glue << "    emit_output(out" << i << ", step, " << i << ", emit, context);\n";
  glue << "    return 0;\n  } catch (const std::exception& e) {\n    set_error(error, error_size, e.what());\n"
       << "  } catch (...) {\n    set_error(error, error_size, \"unknown exception\");\n  }\n  return 1;\n}\n\n"
       << "extern \"C\" void builtscene_model_destroy(void* model) { " << N << "_free(static_cast<" << State
       << "*>(model)); }\n\n"
       << "extern \"C\" int builtscene_model_can_checkpoint(void) { return " << N << "_save != nullptr && " << N
       << "_load != nullptr; }\n\n"
       << "extern \"C\" int builtscene_model_save(void* model, bs_emit_fn emit, void* context, char* error,\n"
       << "                                      size_t error_size) {\n  try {\n    std::string bytes;\n"
       << "    if (!" << N << "_save || !" << N << "_save(*static_cast<const " << State << "*>(model), bytes))\n"
       << "      throw std::runtime_error(\"" << N << "_save failed\");\n"
       << "    emit(context, 0, reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());\n    return 0;\n"
       << "  } catch (const std::exception& e) {\n    set_error(error, error_size, e.what());\n"
       << "  } catch (...) {\n    set_error(error, error_size, \"unknown exception\");\n  }\n  return 1;\n}\n\n"
       << "extern \"C\" int builtscene_model_load(void* model, const unsigned char* data, size_t size, char* error,\n"
       << "                                      size_t error_size) {\n  try {\n"
       << "    const std::string bytes(reinterpret_cast<const char*>(data), size);\n"
       << "    if (!" << N << "_load || !" << N << "_load(*static_cast<" << State << "*>(model), bytes))\n"
       << "      throw std::runtime_error(\"" << N << "_load failed\");\n    return 0;\n"
       << "  } catch (const std::exception& e) {\n    set_error(error, error_size, e.what());\n"
       << "  } catch (...) {\n    set_error(error, error_size, \"unknown exception\");\n  }\n  return 1;\n}\n";
  write_file(out_dir / (N + "_glue.cpp"), glue.str(), out);

  std::ostringstream cm;
  cm << "# Generated by `builtscene couple new-model`: builds the plugin lib" << N
     << ".so that the message wrapper loads.\n"
     << "#   cmake -S . -B build && cmake --build build\n"
     << "cmake_minimum_required(VERSION 3.16)\nproject(" << N << "_model CXX)\nset(CMAKE_CXX_STANDARD 17)\n"
     << "set(CMAKE_CXX_STANDARD_REQUIRED ON)\nif(NOT CMAKE_BUILD_TYPE)\n  set(CMAKE_BUILD_TYPE Release)\nendif()\n"
     << "find_program(LCM_GEN lcm-gen REQUIRED)\nfind_package(nlohmann_json 3 REQUIRED)\n"
     << "file(GLOB lcm_files CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/messages/*.lcm)\n"
     << "set(lcm_out ${CMAKE_CURRENT_BINARY_DIR}/lcmtypes)\n"
     << "add_custom_command(OUTPUT ${lcm_out}/stamp\n"
     << "  COMMAND ${LCM_GEN} --cpp --cpp-hpath ${lcm_out} ${lcm_files}\n"
     << "  COMMAND ${CMAKE_COMMAND} -E touch ${lcm_out}/stamp\n  DEPENDS ${lcm_files}\n"
     << "  VERBATIM)\n"  // arguments escaped for the shell: a folder may hold spaces or quotes
     << "add_custom_target(" << N << "_lcmtypes DEPENDS ${lcm_out}/stamp)\n"
     << "add_library(" << N << " MODULE " << N << ".cpp " << N << "_glue.cpp)\n"
     << "add_dependencies(" << N << " " << N << "_lcmtypes)\n"
     << "target_include_directories(" << N << " PRIVATE ${lcm_out} ${CMAKE_CURRENT_SOURCE_DIR})\n"
     << "target_link_libraries(" << N << " PRIVATE nlohmann_json::nlohmann_json)\n"
     << "set_target_properties(" << N << " PROPERTIES PREFIX \"lib\" LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR})\n";
  write_file(out_dir / "CMakeLists.txt", cm.str(), out);

  const fs::path user_cpp = out_dir / (N + ".cpp");
  if (fs::exists(user_cpp) && !overwrite) {
    out.kept.push_back(user_cpp);
  } else {
    std::ostringstream u;
    u << "// The model function of '" << N << "'. Fill in the body; the message wrapper does all the\n"
      << "// messaging and time-step bookkeeping. Build: cmake -S . -B build && cmake --build build\n"
      << "#include \"" << N << "_model.hpp\"\n\n"
      << "struct " << State << " {\n  nlohmann::json parameters;  // from the config's `parameters`\n"
      << "  // add what your model keeps between steps\n};\n\n"
      << State << "* " << N << "_init(const nlohmann::json& parameters) { return new " << State
      << "{parameters}; }\n\n"
      << "void " << N << "_free(" << State << "* state) { delete state; }\n\n"
      << sig.str() << " {\n  // TODO: compute the outputs from the inputs.\n";
    for (const auto& a : ins) u << "  (void)" << a.name << ";\n";
    u << "  (void)state;\n  (void)step;\n  (void)t;\n";
    for (const auto& a : outs) u << "  " << a.name << " = {};\n";
    u << "}\n\n"
      << "// Optional checkpoints (see " << N << "_model.hpp): uncomment, save what the state keeps\n"
      << "// between steps, and set `checkpoint_every: STEPS` in the config.\n"
      << "// bool " << N << "_save(const " << State << "& state, std::string& bytes) { bytes = ...; return true; }\n"
      << "// bool " << N << "_load(" << State << "& state, const std::string& bytes) { ...; return true; }\n";
    write_file(user_cpp, u.str(), out);
  }

  const fs::path user_py = out_dir / (N + ".py");
  if (fs::exists(user_py) && !overwrite) {
    out.kept.push_back(user_py);
  } else {
    std::ostringstream py;
    py << "#!/usr/bin/env python3\n"
       << "\"\"\"The model function of '" << N << "' as an external program (JSON lines on stdin/stdout).\n"
       << "Use it with `command: [python3, " << N << ".py]` instead of `plugin:` in the model config.\"\"\"\n"
       << "import json\nimport sys\n\n"
       << "# Checkpoints (optional): set True once save() and load() keep everything your model\n"
       << "# keeps between steps; with `checkpoint_every: N` in the config a restarted model\n"
       << "# then resumes from its last checkpoint instead of replaying from step 0.\n"
       << "CHECKPOINTS = False\n\n\n"
       << "def save():\n    return None  # any JSON value\n\n\n"
       << "def load(state):\n    pass\n\n\n"
       << "def " << N << "(parameters, step, t";
    for (const auto& a : ins) py << ", " << a.name;
    py << "):\n    # TODO: compute the outputs from the inputs.\n";
    for (const auto& a : outs) py << "    " << a.name << " = 0\n";
    py << "    return {\n" << py_out.str() << "    }\n\n\n"
       << "def main():\n    parameters = {}\n    for line in sys.stdin:\n        request = json.loads(line)\n"
       << "        if \"init\" in request:\n            parameters = request[\"init\"]\n"
       << "            reply = {\"ok\": True, \"checkpoint\": CHECKPOINTS}\n"
       << "        elif \"save\" in request:\n            reply = {\"state\": save()}\n"
       << "        elif \"load\" in request:\n            load(request[\"load\"])\n            reply = {\"ok\": True}\n"
       << "        else:\n            inputs = request[\"inputs\"]\n"
       << "            try:\n                reply = {\"outputs\": " << N << "(parameters, request[\"step\"], request[\"t\"]";
    for (const auto& a : ins) py << ", " << a.py;
    py << ")}\n            except Exception as e:  # reported by the launcher, which stops the run\n"
       << "                reply = {\"error\": repr(e)}\n"
       << "        sys.stdout.write(json.dumps(reply) + \"\\n\")\n        sys.stdout.flush()\n\n\n"
       << "if __name__ == \"__main__\":\n    main()\n";
    write_file(user_py, py.str(), out);
  }
  return out;
}

}  // namespace builtscene::couple
