// The GPU half of the crowd pipeline: a GLFW window with an OpenGL 3.3+ core context, meshes in
// vertex buffers, the frame's palettes in one texture buffer (persistent-mapped ring with fences
// on GL 4.4+, orphaned and mapped on 3.3; the instances' morph weights follow their palettes),
// meshes' played morph targets in texture buffers, per-instance data in one vertex buffer, and one
// instanced draw per (chain, level) bucket; skinning happens in the vertex shader. Also the GL
// timer queries, and PNG screenshots read from GL_BACK before the swap (needed under Xvfb).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "crowd_animation.hpp"
#include "lod_asset.hpp"

struct GLFWwindow;
typedef struct __GLsync* GLsync;

namespace crowd {

// A buffer rewritten every frame: three sections of a persistently mapped buffer guarded by
// fences when the context has GL_ARB_buffer_storage, else one buffer orphaned and mapped.
class StreamBuffer {
 public:
  void create(unsigned target, size_t capacity, size_t alignment, bool persistent);
  void destroy();
  void* begin();                 // space for up to capacity bytes
  size_t end();                  // unmaps if needed; returns the byte offset of the data written
  void fence();                  // after the draws that read this frame's section
  unsigned buffer() const { return buffer_; }
  size_t capacity() const { return capacity_; }

 private:
  unsigned target_ = 0, buffer_ = 0;
  size_t capacity_ = 0, stride_ = 0;
  bool persistent_ = false;
  unsigned char* mapped_ = nullptr;
  GLsync fences_[3] = {nullptr, nullptr, nullptr};
  int section_ = 0;
};

struct GpuMesh {
  unsigned vao = 0, buffers[6] = {0, 0, 0, 0, 0, 0};
  int32_t index_count = 0;
  int morph_targets = 0;                          // MeshData::morph_targets
  unsigned morph_buffer = 0, morph_texture = 0;   // its MeshData::morph_deltas, where it has targets
};

class GlRenderer {
 public:
  ~GlRenderer();

  // Opens the window and context. False with `error` (one line) when there is no display or the
  // context is older than OpenGL 3.3 core. `orphan_uploads` keeps to the GL 3.3 upload path.
  bool open(int width, int height, bool orphan_uploads, std::string& error);

  std::string renderer() const { return renderer_; }
  std::string version() const { return version_; }
  bool persistent_mapping() const { return persistent_; }
  bool timer_queries() const { return timers_; }
  int framebuffer_width() const { return width_; }
  int framebuffer_height() const { return height_; }

  // Uploads every level mesh of an asset; the mesh id of Asset::meshes[i] is first + i. False
  // with `error` when a mesh's morph targets exceed the texture buffer size.
  bool upload_meshes(const std::vector<MeshData>& meshes, int& first, std::string& error);
  void upload_ground(const std::vector<float>& positions, const std::vector<uint32_t>& indices);
  // Sizes the stream buffers. False with `error` when the palettes exceed the texture buffer size.
  bool reserve(size_t palette_floats, size_t instances, std::string& error);

  float* begin_palettes() { return static_cast<float*>(palettes_.begin()); }
  InstanceGpu* begin_instances() { return static_cast<InstanceGpu*>(instances_.begin()); }
  void end_uploads(size_t palette_floats);

  // Clears, draws the ground and one instanced draw per bucket (mesh ids resolved by mesh_of),
  // timing the draws with a timer query where available.
  void draw(const glm::mat4& view_projection, const std::vector<Bucket>& buckets, const std::vector<int>& mesh_of_bucket,
            bool level_colors);
  // Reads GL_BACK (before the swap) and writes a PNG atomically. False with `error` on failure.
  bool screenshot(const std::string& path, std::string& error);
  void swap();
  // GPU milliseconds of a finished earlier frame's draws, or a negative value if none is ready.
  double poll_gpu_ms();

 private:
  GLFWwindow* window_ = nullptr;
  std::string renderer_, version_;
  bool persistent_ = false, timers_ = false, buffer_range_ = false;
  int width_ = 0, height_ = 0;
  unsigned character_program_ = 0, ground_program_ = 0, palette_texture_ = 0;
  int u_view_projection_ = -1, u_tint_amount_ = -1, u_morph_targets_ = -1, u_ground_view_projection_ = -1;
  std::vector<GpuMesh> meshes_;
  GpuMesh ground_;
  StreamBuffer palettes_, instances_;
  size_t palette_offset_ = 0, instance_offset_ = 0, palette_bytes_ = 0;
  unsigned queries_[4] = {0, 0, 0, 0};
  int query_next_ = 0, queries_pending_ = 0;
};

}  // namespace crowd
