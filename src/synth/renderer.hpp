#pragma once
// Z-buffer rasterizer of textured rectangles. Each surface is clipped at the near plane,
// projected, and scan-converted; per pixel the depth comes from the surface's plane
// (exact for the ray through the pixel centre), texture coordinates are perspective-correct
// and sampled trilinearly from a mip pyramid chosen by the pixel's footprint, and shading is
// Lambertian from precomputed light maps (point lights with hard shadows, plus ambient).
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "synth/scene.hpp"

namespace builtscene::synth {

struct RenderOutput {
  cv::Mat bgr;        // CV_32FC3, linear radiance in 8-bit units (0..255 for a well-exposed white)
  cv::Mat depth;      // CV_32F, metres along the optical axis, 0 where nothing was hit
  cv::Mat incidence;  // CV_32F, |cos| of the angle between the viewing ray and the surface normal
};

class Renderer {
 public:
  Renderer(const Scene& scene, const PinholeCamera& camera);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Renders the view from camera pose T_wc. `threads` > 1 splits rows into bands; the result
  // does not depend on the number of threads.
  void render(const SE3& T_wc, RenderOutput& out, int threads = 1) const;

  const std::vector<Surface>& surfaces() const { return surfaces_; }
  const PinholeCamera& camera() const { return camera_; }

  struct MipTexture;
  struct LightMap;

 private:
  void render_rows(const SE3& T_cw, RenderOutput& out, int row_begin, int row_end) const;

  PinholeCamera camera_;
  std::vector<Surface> surfaces_;
  std::vector<Material> materials_;
  std::vector<int> material_texture_;           // material -> index in textures_
  std::vector<std::unique_ptr<MipTexture>> textures_;
  std::vector<std::unique_ptr<LightMap>> lightmaps_;  // one per surface
};

}  // namespace builtscene::synth
