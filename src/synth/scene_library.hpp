#pragma once
// The named generated worlds: lab-room, corridor-loop, office, low-texture and demo.
#include <string>
#include <vector>

#include "synth/scene.hpp"

namespace builtscene::synth {

std::vector<std::string> scene_names();
bool is_scene_name(const std::string& name);
// Builds a scene (geometry, textures, lights, robot loop). The geometry is fixed for a name;
// throws std::invalid_argument for an unknown name.
Scene build_scene(const std::string& name);

}  // namespace builtscene::synth
