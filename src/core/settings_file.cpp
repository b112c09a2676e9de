#include "core/settings_file.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/errors.hpp"

namespace builtscene {

SettingsFile SettingsFile::load(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw_input_error(path, 0, "cannot open settings file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse(ss.str(), path);
}

SettingsFile SettingsFile::parse(const std::string& text_in, const std::filesystem::path& name) {
  std::string text = text_in;
  // OpenCV writes "%YAML:1.0"; yaml-cpp wants "%YAML 1.0" or nothing. Blank it, keeping lines.
  if (text.rfind("%YAML:", 0) == 0) {
    const auto eol = text.find('\n');
    text.replace(0, eol == std::string::npos ? text.size() : eol, "");
  }
  SettingsFile s;
  s.path_ = name;
  try {
    s.root_ = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw_input_error(name, static_cast<std::size_t>(e.mark.line + 1), "invalid YAML: " + e.msg);
  }
  if (!s.root_.IsMap()) throw_input_error(name, 0, "expected a map of settings (key: value)");
  return s;
}

bool SettingsFile::has(const std::string& key) const { return root_[key].IsDefined(); }

YAML::Node SettingsFile::node(const std::string& key) const {
  YAML::Node n = root_[key];
  if (!n.IsDefined()) throw_input_error(path_, 0, "missing field '" + key + "'");
  return n;
}

double SettingsFile::get_double(const std::string& key) const {
  const YAML::Node n = node(key);
  try {
    const double v = n.as<double>();
    if (!std::isfinite(v)) throw YAML::Exception(n.Mark(), "not finite");
    return v;
  } catch (const YAML::Exception&) {
    throw_input_error(path_, static_cast<std::size_t>(n.Mark().line + 1),
                      "field '" + key + "' must be a finite number");
  }
}

double SettingsFile::get_double(const std::string& key, double fallback) const {
  return has(key) ? get_double(key) : fallback;
}

int SettingsFile::get_int(const std::string& key) const {
  const double v = get_double(key);
  if (v != std::floor(v) || std::abs(v) > 1e9)
    throw_input_error(path_, static_cast<std::size_t>(root_[key].Mark().line + 1),
                      "field '" + key + "' must be an integer");
  return static_cast<int>(v);
}

int SettingsFile::get_int(const std::string& key, int fallback) const { return has(key) ? get_int(key) : fallback; }

std::string SettingsFile::get_string(const std::string& key, const std::string& fallback) const {
  if (!has(key)) return fallback;
  return root_[key].as<std::string>();
}

}  // namespace builtscene
