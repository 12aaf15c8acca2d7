// GLFW window, OpenGL 3.3+ buffers and shaders, instanced GPU skinning draws, timer queries and
// screenshots (gl_renderer.hpp).
#include "gl_renderer.hpp"

#include <GLFW/glfw3.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include <glm/gtc/type_ptr.hpp>
#include <stb_image_write.h>

namespace crowd {

namespace {

std::string glfw_error;  // the last GLFW error, for the one-line message

void on_glfw_error(int code, const char* description) {
  glfw_error = "GLFW error " + std::to_string(code) + ": " + (description ? description : "");
}

// Skinning in the vertex shader: the palette holds 3 rows (RGBA32F texels) of each joint's
// affine matrix; a vertex blends the rows of its 4 or 8 joints by weight (linear blend
// skinning). A mesh of 4 influences leaves the second set's arrays off: its weights read the
// constant 0 (set in init). Before skinning, a mesh with morph targets adds each target's
// position and normal deltas at the instance's weights, which follow its palette in the same
// buffer (4 a texel).
const char* kCharacterVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_color;
layout(location = 3) in uvec4 a_joints;
layout(location = 4) in vec4 a_weights;
layout(location = 5) in vec4 a_placement;  // x, y, z, yaw
layout(location = 6) in uvec3 a_instance;  // palette base, level, morph weights base (texels)
layout(location = 7) in uvec4 a_joints_1;
layout(location = 8) in vec4 a_weights_1;
uniform samplerBuffer u_palette;
uniform samplerBuffer u_morph_deltas;  // (V, T, 2) texels: position delta, normal delta
uniform int u_morph_targets;           // T, 0 for a mesh without played morph weights
uniform mat4 u_view_projection;
uniform float u_tint_amount;
out vec3 v_normal;
out vec3 v_color;
const vec3 kTints[8] = vec3[8](vec3(0.10, 0.75, 0.20), vec3(0.95, 0.85, 0.10), vec3(0.95, 0.45, 0.05),
                               vec3(0.90, 0.10, 0.10), vec3(0.70, 0.15, 0.85), vec3(0.15, 0.35, 0.95),
                               vec3(0.10, 0.85, 0.90), vec3(0.95, 0.95, 0.95));
vec4 r0 = vec4(0.0), r1 = vec4(0.0), r2 = vec4(0.0);
void blend(uvec4 joints, vec4 weights) {
  for (int k = 0; k < 4; ++k) {
    float w = weights[k];
    if (w > 0.0) {
      int base = int(a_instance.x) + 3 * int(joints[k]);
      r0 += w * texelFetch(u_palette, base);
      r1 += w * texelFetch(u_palette, base + 1);
      r2 += w * texelFetch(u_palette, base + 2);
    }
  }
}
void main() {
  vec3 position = a_position, normal = a_normal;
  for (int t = 0; t < u_morph_targets; ++t) {
    float w = texelFetch(u_palette, int(a_instance.z) + t / 4)[t % 4];
    if (w != 0.0) {
      int delta = 2 * (gl_VertexID * u_morph_targets + t);
      position += w * texelFetch(u_morph_deltas, delta).xyz;
      normal += w * texelFetch(u_morph_deltas, delta + 1).xyz;
    }
  }
  blend(a_joints, a_weights);
  blend(a_joints_1, a_weights_1);
  vec4 p = vec4(position, 1.0);
  vec3 skinned = vec3(dot(r0, p), dot(r1, p), dot(r2, p));
  vec3 n = vec3(dot(r0.xyz, normal), dot(r1.xyz, normal), dot(r2.xyz, normal));
  float c = cos(a_placement.w), s = sin(a_placement.w);
  mat3 yaw = mat3(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);
  v_normal = yaw * n;
  v_color = mix(a_color, kTints[min(a_instance.y, 7u)], u_tint_amount);
  gl_Position = u_view_projection * vec4(yaw * skinned + a_placement.xyz, 1.0);
}
)";

const char* kCharacterFragment = R"(#version 330 core
in vec3 v_normal;
in vec3 v_color;
out vec4 fragment;
void main() {
  vec3 n = normalize(v_normal);
  float light = 0.35 + 0.65 * abs(dot(n, normalize(vec3(0.4, 0.8, 0.45))));
  fragment = vec4(v_color * light, 1.0);
}
)";

const char* kGroundVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
uniform mat4 u_view_projection;
out vec3 v_world;
void main() {
  v_world = a_position;
  gl_Position = u_view_projection * vec4(a_position, 1.0);
}
)";

const char* kGroundFragment = R"(#version 330 core
in vec3 v_world;
out vec4 fragment;
void main() {
  vec3 n = normalize(cross(dFdx(v_world), dFdy(v_world)));
  float light = 0.45 + 0.55 * abs(dot(n, normalize(vec3(0.4, 0.8, 0.45))));
  fragment = vec4(vec3(0.36, 0.40, 0.30) * light, 1.0);
}
)";

unsigned compile(unsigned kind, const char* source, std::string& log) {
  const unsigned shader = glCreateShader(kind);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char text[2048] = {};
    glGetShaderInfoLog(shader, sizeof text, nullptr, text);
    log = text;
  }
  return shader;
}

unsigned link(const char* vertex, const char* fragment, std::string& error) {
  std::string log;
  const unsigned vs = compile(GL_VERTEX_SHADER, vertex, log), fs = compile(GL_FRAGMENT_SHADER, fragment, log);
  const unsigned program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok && log.empty()) {
    char text[2048] = {};
    glGetProgramInfoLog(program, sizeof text, nullptr, text);
    log = text;
  }
  glDeleteShader(vs);
  glDeleteShader(fs);
  if (!ok) error = "shader: " + log;
  return ok ? program : 0;
}

void float_attribute(unsigned index, unsigned buffer, const std::vector<float>& data, int size) {
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(index);
  glVertexAttribPointer(index, size, GL_FLOAT, GL_FALSE, 0, nullptr);
}

// Skin influences, `per_vertex` values a vertex in sets of 4: set s at attribute `first` + 4 s
// (joints 3 and 7, weights 4 and 8).
template <typename T>
void influence_attribute(unsigned first, unsigned buffer, const std::vector<T>& data, int per_vertex) {
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(T)), data.data(), GL_STATIC_DRAW);
  const GLsizei stride = per_vertex * static_cast<GLsizei>(sizeof(T));
  for (int set = 0; 4 * set < per_vertex; ++set) {
    const GLuint location = first + 4 * static_cast<GLuint>(set);
    const void* offset = reinterpret_cast<const void*>(4 * static_cast<size_t>(set) * sizeof(T));
    glEnableVertexAttribArray(location);
    if constexpr (std::is_integral_v<T>)
      glVertexAttribIPointer(location, 4, GL_UNSIGNED_SHORT, stride, offset);
    else
      glVertexAttribPointer(location, 4, GL_FLOAT, GL_FALSE, stride, offset);
  }
}

bool has_extension(const char* name) {
  GLint count = 0;
  glGetIntegerv(GL_NUM_EXTENSIONS, &count);
  for (GLint i = 0; i < count; ++i)
    if (std::strcmp(reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, static_cast<GLuint>(i))), name) == 0)
      return true;
  return false;
}

}  // namespace

void StreamBuffer::create(unsigned target, size_t capacity, size_t alignment, bool persistent) {
  destroy();
  target_ = target;
  capacity_ = capacity;
  persistent_ = persistent;
  stride_ = (capacity + alignment - 1) / alignment * alignment;
  glGenBuffers(1, &buffer_);
  glBindBuffer(target_, buffer_);
  if (persistent_) {
    const GLbitfield flags = GL_MAP_WRITE_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
    glBufferStorage(target_, static_cast<GLsizeiptr>(3 * stride_), nullptr, flags);
    mapped_ = static_cast<unsigned char*>(glMapBufferRange(target_, 0, static_cast<GLsizeiptr>(3 * stride_), flags));
  } else {
    glBufferData(target_, static_cast<GLsizeiptr>(stride_), nullptr, GL_STREAM_DRAW);
  }
}

void StreamBuffer::destroy() {
  for (GLsync& fence : fences_)
    if (fence) glDeleteSync(fence), fence = nullptr;
  if (buffer_) {
    if (persistent_ && mapped_) {
      glBindBuffer(target_, buffer_);
      glUnmapBuffer(target_);
    }
    glDeleteBuffers(1, &buffer_);
  }
  buffer_ = 0;
  mapped_ = nullptr;
}

void* StreamBuffer::begin() {
  glBindBuffer(target_, buffer_);
  if (persistent_) {
    section_ = (section_ + 1) % 3;
    if (fences_[section_]) {  // the GPU may still read what this section held three frames ago
      glClientWaitSync(fences_[section_], GL_SYNC_FLUSH_COMMANDS_BIT, 1000000000ull);
      glDeleteSync(fences_[section_]);
      fences_[section_] = nullptr;
    }
    return mapped_ + static_cast<size_t>(section_) * stride_;
  }
  // Orphan the old storage (the driver keeps it for draws in flight) and map fresh memory.
  glBufferData(target_, static_cast<GLsizeiptr>(stride_), nullptr, GL_STREAM_DRAW);
  return glMapBufferRange(target_, 0, static_cast<GLsizeiptr>(stride_), GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
}

size_t StreamBuffer::end() {
  if (persistent_) return static_cast<size_t>(section_) * stride_;
  glBindBuffer(target_, buffer_);
  glUnmapBuffer(target_);
  return 0;
}

void StreamBuffer::fence() {
  if (persistent_) fences_[section_] = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
}

GlRenderer::~GlRenderer() {
  if (!window_) return;
  palettes_.destroy();
  instances_.destroy();
  glfwDestroyWindow(window_);
  glfwTerminate();
}

bool GlRenderer::open(int width, int height, bool orphan_uploads, std::string& error) {
  glfwSetErrorCallback(on_glfw_error);
  if (!glfwInit()) {
    error = "cannot initialise GLFW (no display? run under xvfb-run -a -s \"-screen 0 1280x720x24\"): " + glfw_error;
    return false;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
  window_ = glfwCreateWindow(width, height, "animlod crowd", nullptr, nullptr);
  if (!window_) {
    error = "cannot create an OpenGL 3.3 core context (the driver or GPU is too old?): " + glfw_error;
    glfwTerminate();
    return false;
  }
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(0);
  glfwGetFramebufferSize(window_, &width_, &height_);
  renderer_ = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  version_ = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  const int version = 10 * major + minor;
  persistent_ = version >= 44 || has_extension("GL_ARB_buffer_storage");
  buffer_range_ = version >= 43 || has_extension("GL_ARB_texture_buffer_range");
  persistent_ = persistent_ && buffer_range_ && !orphan_uploads;  // a ring section is bound as a buffer range
  if (version < 33) {
    error = "OpenGL " + version_ + " is older than 3.3 core, which animlod_crowd needs";
    return false;
  }
  GLint bits = 0;
  glGetQueryiv(GL_TIME_ELAPSED, GL_QUERY_COUNTER_BITS, &bits);
  timers_ = bits > 0;
  if (timers_) glGenQueries(4, queries_);

  character_program_ = link(kCharacterVertex, kCharacterFragment, error);
  if (!character_program_) return false;
  ground_program_ = link(kGroundVertex, kGroundFragment, error);
  if (!ground_program_) return false;
  u_view_projection_ = glGetUniformLocation(character_program_, "u_view_projection");
  u_tint_amount_ = glGetUniformLocation(character_program_, "u_tint_amount");
  u_morph_targets_ = glGetUniformLocation(character_program_, "u_morph_targets");
  u_ground_view_projection_ = glGetUniformLocation(ground_program_, "u_view_projection");
  glUseProgram(character_program_);
  glUniform1i(glGetUniformLocation(character_program_, "u_palette"), 0);
  glUniform1i(glGetUniformLocation(character_program_, "u_morph_deltas"), 1);
  glVertexAttribI4ui(7, 0, 0, 0, 0);  // the second influence set of 4-influence meshes
  glVertexAttrib4f(8, 0.0f, 0.0f, 0.0f, 0.0f);
  glGenTextures(1, &palette_texture_);
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);  // exporters disagree on winding; skinned limbs show both sides
  glViewport(0, 0, width_, height_);
  return true;
}

bool GlRenderer::upload_meshes(const std::vector<MeshData>& meshes, int& first, std::string& error) {
  GLint texels = 0;
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &texels);
  first = static_cast<int>(meshes_.size());
  for (const MeshData& mesh : meshes) {
    GpuMesh gpu;
    glGenVertexArrays(1, &gpu.vao);
    glBindVertexArray(gpu.vao);
    glGenBuffers(6, gpu.buffers);
    float_attribute(0, gpu.buffers[0], mesh.positions, 3);
    float_attribute(1, gpu.buffers[1], mesh.normals, 3);
    float_attribute(2, gpu.buffers[2], mesh.colors, 3);
    influence_attribute(3, gpu.buffers[3], mesh.joints, mesh.influences);
    influence_attribute(4, gpu.buffers[4], mesh.weights, mesh.influences);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, gpu.buffers[5]);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(mesh.indices.size() * sizeof(uint32_t)),
                 mesh.indices.data(), GL_STATIC_DRAW);
    glEnableVertexAttribArray(5);
    glEnableVertexAttribArray(6);
    glVertexAttribDivisor(5, 1);
    glVertexAttribDivisor(6, 1);
    gpu.index_count = static_cast<int32_t>(mesh.indices.size());
    gpu.morph_targets = mesh.morph_targets;
    if (mesh.morph_targets > 0) {
      if (mesh.morph_deltas.size() / 4 > static_cast<size_t>(texels)) {
        error = "a mesh of " + std::to_string(mesh.vertex_count()) + " vertices and " + std::to_string(mesh.morph_targets) +
                " played morph targets needs " + std::to_string(mesh.morph_deltas.size() / 4) +
                " texels, the texture buffer holds " + std::to_string(texels);
        return false;
      }
      glGenBuffers(1, &gpu.morph_buffer);
      glBindBuffer(GL_TEXTURE_BUFFER, gpu.morph_buffer);
      glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(mesh.morph_deltas.size() * sizeof(float)),
                   mesh.morph_deltas.data(), GL_STATIC_DRAW);
      glGenTextures(1, &gpu.morph_texture);
      glBindTexture(GL_TEXTURE_BUFFER, gpu.morph_texture);
      glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, gpu.morph_buffer);
    }
    meshes_.push_back(gpu);
  }
  glBindVertexArray(0);
  return true;
}

void GlRenderer::upload_ground(const std::vector<float>& positions, const std::vector<uint32_t>& indices) {
  glGenVertexArrays(1, &ground_.vao);
  glBindVertexArray(ground_.vao);
  glGenBuffers(2, ground_.buffers);
  float_attribute(0, ground_.buffers[0], positions, 3);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ground_.buffers[1]);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(uint32_t)), indices.data(),
               GL_STATIC_DRAW);
  ground_.index_count = static_cast<int32_t>(indices.size());
  glBindVertexArray(0);
}

bool GlRenderer::reserve(size_t palette_floats, size_t instances, std::string& error) {
  GLint texels = 0, alignment = 1;
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &texels);
  if (buffer_range_) glGetIntegerv(GL_TEXTURE_BUFFER_OFFSET_ALIGNMENT, &alignment);
  if (palette_floats / 4 > static_cast<size_t>(texels)) {
    error = "the palettes need " + std::to_string(palette_floats / 4) + " texels, the texture buffer holds " +
            std::to_string(texels) + ": use fewer characters";
    return false;
  }
  palettes_.create(GL_TEXTURE_BUFFER, std::max<size_t>(palette_floats, 12) * sizeof(float),
                   static_cast<size_t>(std::max(alignment, 256)), persistent_);
  instances_.create(GL_ARRAY_BUFFER, std::max<size_t>(instances, 1) * sizeof(InstanceGpu), 256, persistent_);
  glBindTexture(GL_TEXTURE_BUFFER, palette_texture_);
  if (!persistent_) glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, palettes_.buffer());
  return true;
}

void GlRenderer::end_uploads(size_t palette_floats) {
  palette_offset_ = palettes_.end();
  instance_offset_ = instances_.end();
  palette_bytes_ = std::max<size_t>(palette_floats, 12) * sizeof(float);
}

void GlRenderer::draw(const glm::mat4& view_projection, const std::vector<Bucket>& buckets,
                      const std::vector<int>& mesh_of_bucket, bool level_colors) {
  if (timers_ && queries_pending_ < 4) {
    glBeginQuery(GL_TIME_ELAPSED, queries_[query_next_]);
  }
  glClearColor(0.55f, 0.65f, 0.78f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glUseProgram(ground_program_);
  glUniformMatrix4fv(u_ground_view_projection_, 1, GL_FALSE, glm::value_ptr(view_projection));
  glBindVertexArray(ground_.vao);
  glDrawElements(GL_TRIANGLES, ground_.index_count, GL_UNSIGNED_INT, nullptr);

  glUseProgram(character_program_);
  glUniformMatrix4fv(u_view_projection_, 1, GL_FALSE, glm::value_ptr(view_projection));
  glUniform1f(u_tint_amount_, level_colors ? 0.85f : 0.0f);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_BUFFER, palette_texture_);
  if (persistent_)
    glTexBufferRange(GL_TEXTURE_BUFFER, GL_RGBA32F, palettes_.buffer(), static_cast<GLintptr>(palette_offset_),
                     static_cast<GLsizeiptr>(palette_bytes_));
  glBindBuffer(GL_ARRAY_BUFFER, instances_.buffer());
  for (size_t b = 0; b < buckets.size(); ++b) {
    const Bucket& bucket = buckets[b];
    const GpuMesh& mesh = meshes_[static_cast<size_t>(mesh_of_bucket[b])];
    glBindVertexArray(mesh.vao);
    // Point the per-instance attributes at this bucket's instances (GL 3.3: no base instance).
    const size_t offset = instance_offset_ + bucket.first * sizeof(InstanceGpu);
    glVertexAttribPointer(5, 4, GL_FLOAT, GL_FALSE, sizeof(InstanceGpu), reinterpret_cast<const void*>(offset));
    glVertexAttribIPointer(6, 3, GL_UNSIGNED_INT, sizeof(InstanceGpu),
                           reinterpret_cast<const void*>(offset + offsetof(InstanceGpu, palette_base)));
    glUniform1i(u_morph_targets_, mesh.morph_targets);
    if (mesh.morph_targets > 0) {
      glActiveTexture(GL_TEXTURE1);
      glBindTexture(GL_TEXTURE_BUFFER, mesh.morph_texture);
      glActiveTexture(GL_TEXTURE0);
    }
    glDrawElementsInstanced(GL_TRIANGLES, mesh.index_count, GL_UNSIGNED_INT, nullptr,
                            static_cast<GLsizei>(bucket.count));
  }
  glBindVertexArray(0);
  if (timers_ && queries_pending_ < 4) {
    glEndQuery(GL_TIME_ELAPSED);
    query_next_ = (query_next_ + 1) % 4;
    ++queries_pending_;
  }
  palettes_.fence();
  instances_.fence();
}

double GlRenderer::poll_gpu_ms() {
  if (!timers_ || queries_pending_ == 0) return -1.0;
  const int oldest = (query_next_ + 4 - queries_pending_) % 4;
  GLint available = 0;
  glGetQueryObjectiv(queries_[oldest], GL_QUERY_RESULT_AVAILABLE, &available);
  if (!available) return -1.0;
  GLuint64 nanoseconds = 0;
  glGetQueryObjectui64v(queries_[oldest], GL_QUERY_RESULT, &nanoseconds);
  --queries_pending_;
  return static_cast<double>(nanoseconds) * 1e-6;
}

bool GlRenderer::screenshot(const std::string& path, std::string& error) {
  std::vector<unsigned char> pixels(static_cast<size_t>(width_) * static_cast<size_t>(height_) * 3);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_, height_, GL_RGB, GL_UNSIGNED_BYTE, pixels.data());
  std::vector<unsigned char> flipped(pixels.size());
  const size_t row = static_cast<size_t>(width_) * 3;
  for (int y = 0; y < height_; ++y)
    std::memcpy(flipped.data() + static_cast<size_t>(y) * row, pixels.data() + static_cast<size_t>(height_ - 1 - y) * row, row);
  const std::string partial = path + ".partial.png";  // renamed once complete
  if (!stbi_write_png(partial.c_str(), width_, height_, 3, flipped.data(), static_cast<int>(row)) ||
      std::rename(partial.c_str(), path.c_str()) != 0) {
    std::remove(partial.c_str());
    error = path + ": cannot write the screenshot";
    return false;
  }
  return true;
}

void GlRenderer::swap() {
  glfwSwapBuffers(window_);
  glfwPollEvents();
}

}  // namespace crowd
