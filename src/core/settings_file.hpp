#pragma once
// ORB-SLAM-style settings files (camera.yaml): flat keys such as `Camera.fx`, optionally
// behind an OpenCV `%YAML:1.0` directive line that yaml-cpp does not accept. Typed getters
// throw InputError naming the file, the line and the key.
#include <filesystem>
#include <optional>
#include <string>

#include <yaml-cpp/yaml.h>

namespace builtscene {

class SettingsFile {
 public:
  static SettingsFile load(const std::filesystem::path& path);
  static SettingsFile parse(const std::string& text, const std::filesystem::path& name);

  bool has(const std::string& key) const;
  double get_double(const std::string& key) const;
  double get_double(const std::string& key, double fallback) const;
  int get_int(const std::string& key) const;
  int get_int(const std::string& key, int fallback) const;
  std::string get_string(const std::string& key, const std::string& fallback) const;

  const std::filesystem::path& path() const { return path_; }
  const YAML::Node& root() const { return root_; }

 private:
  std::filesystem::path path_;
  YAML::Node root_;
  YAML::Node node(const std::string& key) const;  // throws when missing
};

}  // namespace builtscene
