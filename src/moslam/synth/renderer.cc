#include "moslam/synth/renderer.h"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/osmesa.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <utility>

#include <spdlog/spdlog.h>
#include "moslam/util/check.h"

namespace moslam::synth {
namespace {

// Threads of llvmpipe's rasterizer when the user did not choose: the project's machines have 2
// cores; a fixed count keeps the set-up (not the output, which is tile-deterministic) identical.
constexpr const char* kDefaultLpThreads = "2";

const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 position;   // cube corner in [-1, 1]^3
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 face_uv;    // position on the face in [-1, 1]^2 (y up on side faces)
layout(location = 3) in vec2 face_axes;  // box axes (0, 1, 2) along face_uv.x and face_uv.y
layout(location = 4) in vec3 vertex_colour;  // meshes: multiplies the texture (boxes: 1)
uniform int mesh;         // 1: a mesh in world coordinates with its own texture coordinates
uniform mat4 model;       // T_world_box * diag(half)
uniform mat4 view;        // T_cam_world (OpenCV camera axes)
uniform mat4 projection;  // intrinsics, image row 0 at NDC y = -1
uniform vec3 half_size;
uniform float tile;
uniform vec2 uv_offset;
out vec2 uv;
out float z_cam;
out vec3 normal_world;
out vec3 colour_mul;
void main() {
  colour_mul = vertex_colour;
  if (mesh == 1) {
    vec4 p_cam = view * vec4(position, 1.0);
    z_cam = p_cam.z;
    gl_Position = projection * p_cam;
    normal_world = normal;
    uv = face_uv;
    return;
  }
  vec4 p_cam = view * (model * vec4(position, 1.0));
  z_cam = p_cam.z;
  gl_Position = projection * p_cam;
  normal_world = normalize(mat3(model) * normal);
  if (tile > 0.0) {
    vec2 metres = vec2(face_uv.x * half_size[int(face_axes.x)], face_uv.y * half_size[int(face_axes.y)]);
    uv = vec2(metres.x, -metres.y) / tile + uv_offset;
  } else {
    uv = vec2(0.5 + 0.5 * face_uv.x, 0.5 - 0.5 * face_uv.y);
  }
}
)";

const char* kFragmentShader = R"(#version 330 core
in vec2 uv;
in float z_cam;
in vec3 normal_world;
in vec3 colour_mul;
uniform int mesh;
uniform sampler2D tex;
uniform vec3 light;   // unit direction the light travels
uniform float ambient;
uniform float diffuse;
uniform float tint;
uniform uvec2 label;  // class id, instance id
layout(location = 0) out vec4 colour;
layout(location = 1) out float depth;
layout(location = 2) out uvec2 ids;
void main() {
  if (mesh == 1) {
    // Meshes have outward normals: one-sided diffuse light plus an ambient term brighter from
    // the sky than from the floor, which gives round bodies their shading.
    vec3 n = normalize(normal_world);
    float shade = ambient * (0.82 + 0.18 * n.z) + diffuse * max(0.0, -dot(n, light));
    colour = vec4(texture(tex, uv).rgb * colour_mul * shade, 1.0);
  } else {
    // Boxes are lit from both sides (rooms are seen from inside).
    float shade = (ambient + diffuse * abs(dot(normalize(normal_world), light))) * tint;
    colour = vec4(texture(tex, uv).rgb * shade, 1.0);
  }
  depth = z_cam;
  ids = label;
}
)";

GLuint Compile(GLenum type, const char* source) {
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    std::array<char, 4096> log{};
    glGetShaderInfoLog(shader, static_cast<GLsizei>(log.size()), nullptr, log.data());
    throw std::runtime_error(std::string("synth renderer: shader compile failed: ") + log.data());
  }
  return shader;
}

// Vertices of the unit cube [-1, 1]^3: per face 6 vertices of (position, normal, face uv, axes).
std::vector<float> CubeVertices() {
  std::vector<float> v;
  // For each face: normal axis n and sign s; u and v axes chosen so side faces have v = z (up).
  const int faces[6][4] = {{0, 1, 1, 2},  {0, -1, 1, 2}, {1, 1, 0, 2},
                           {1, -1, 0, 2}, {2, 1, 0, 1},  {2, -1, 0, 1}};
  const float corners[6][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, -1}, {1, 1}, {-1, 1}};
  for (const auto& f : faces) {
    for (const auto& c : corners) {
      float p[3] = {0, 0, 0}, n[3] = {0, 0, 0};
      p[f[0]] = static_cast<float>(f[1]);
      n[f[0]] = static_cast<float>(f[1]);
      p[f[2]] = c[0];
      p[f[3]] = c[1];
      v.insert(v.end(), {p[0], p[1], p[2], n[0], n[1], n[2], c[0], c[1], static_cast<float>(f[2]),
                         static_cast<float>(f[3])});
    }
  }
  return v;
}

std::array<float, 16> ToGl(const Eigen::Matrix4d& m) {
  std::array<float, 16> out{};
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) out[static_cast<size_t>(c * 4 + r)] = static_cast<float>(m(r, c));
  }
  return out;
}

// OpenGL projection from pinhole intrinsics. OpenCV puts pixel i's centre at coordinate i, GL at
// i + 0.5; image row 0 goes to NDC y = -1 so that glReadPixels returns rows top-down.
Eigen::Matrix4d Projection(const camera::PinholeOptions& c, double near, double far) {
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  p(0, 0) = 2.0 * c.fx / c.width;
  p(0, 2) = 2.0 * (c.cx + 0.5) / c.width - 1.0;
  p(1, 1) = 2.0 * c.fy / c.height;
  p(1, 2) = 2.0 * (c.cy + 0.5) / c.height - 1.0;
  p(2, 2) = (far + near) / (far - near);
  p(2, 3) = -2.0 * far * near / (far - near);
  p(3, 2) = 1.0;
  return p;
}

}  // namespace

struct Renderer::Impl {
  int width = 0, height = 0;
  OSMesaContext context = nullptr;
  std::vector<unsigned char> dummy;  // OSMesa needs a default buffer; we draw into the FBO
  GLuint program = 0, vao = 0, vbo = 0, fbo = 0;
  GLuint mesh_vao = 0, mesh_vbo = 0, mesh_ebo = 0;
  GLuint white = 0;                 // 4x4 white texture for plain-coloured mesh parts (texture -1)
  GLuint fabric = 0;                // plain cloth (texture -2, MakeFabricTexture)
  std::vector<float> mesh_data;     // per-frame vertex upload buffer
  std::array<GLuint, 4> targets{};  // colour, depth (R32F), ids (RG16UI), depth buffer
  std::vector<GLuint> textures;
  GLint u_model = -1, u_view = -1, u_projection = -1, u_half = -1, u_tile = -1, u_offset = -1;
  GLint u_light = -1, u_ambient = -1, u_diffuse = -1, u_tint = -1, u_label = -1, u_mesh = -1;
  cv::Mat ids;  // CV_16UC2 read-back buffer
};

Renderer::Renderer(int width, int height, const TextureSet& texture_set)
    : impl_(std::make_unique<Impl>()) {
  MOSLAM_CHECK(width > 0 && height > 0);
  setenv("LP_NUM_THREADS", kDefaultLpThreads, /*overwrite=*/0);
  Impl& g = *impl_;
  g.width = width;
  g.height = height;
  const int attributes[] = {OSMESA_FORMAT,
                            OSMESA_RGBA,
                            OSMESA_DEPTH_BITS,
                            24,
                            OSMESA_PROFILE,
                            OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION,
                            3,
                            OSMESA_CONTEXT_MINOR_VERSION,
                            3,
                            0};
  g.context = OSMesaCreateContextAttribs(attributes, nullptr);
  if (g.context == nullptr) throw std::runtime_error("synth renderer: OSMesa context failed");
  g.dummy.resize(16 * 16 * 4);
  if (!OSMesaMakeCurrent(g.context, g.dummy.data(), GL_UNSIGNED_BYTE, 16, 16)) {
    throw std::runtime_error("synth renderer: OSMesaMakeCurrent failed");
  }

  g.program = glCreateProgram();
  const GLuint vs = Compile(GL_VERTEX_SHADER, kVertexShader);
  const GLuint fs = Compile(GL_FRAGMENT_SHADER, kFragmentShader);
  glAttachShader(g.program, vs);
  glAttachShader(g.program, fs);
  glLinkProgram(g.program);
  GLint ok = 0;
  glGetProgramiv(g.program, GL_LINK_STATUS, &ok);
  if (!ok) throw std::runtime_error("synth renderer: shader link failed");
  glDeleteShader(vs);
  glDeleteShader(fs);
  glUseProgram(g.program);
  g.u_model = glGetUniformLocation(g.program, "model");
  g.u_view = glGetUniformLocation(g.program, "view");
  g.u_projection = glGetUniformLocation(g.program, "projection");
  g.u_half = glGetUniformLocation(g.program, "half_size");
  g.u_tile = glGetUniformLocation(g.program, "tile");
  g.u_offset = glGetUniformLocation(g.program, "uv_offset");
  g.u_light = glGetUniformLocation(g.program, "light");
  g.u_ambient = glGetUniformLocation(g.program, "ambient");
  g.u_diffuse = glGetUniformLocation(g.program, "diffuse");
  g.u_tint = glGetUniformLocation(g.program, "tint");
  g.u_label = glGetUniformLocation(g.program, "label");
  g.u_mesh = glGetUniformLocation(g.program, "mesh");
  glUniform1i(glGetUniformLocation(g.program, "tex"), 0);

  const std::vector<float> cube = CubeVertices();
  glGenVertexArrays(1, &g.vao);
  glBindVertexArray(g.vao);
  glGenBuffers(1, &g.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(cube.size() * sizeof(float)), cube.data(),
               GL_STATIC_DRAW);
  const int sizes[4] = {3, 3, 2, 2};
  size_t offset = 0;
  for (GLuint a = 0; a < 4; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, 10 * sizeof(float),
                          reinterpret_cast<const void*>(offset * sizeof(float)));
    offset += static_cast<size_t>(sizes[a]);
  }
  glVertexAttrib3f(4, 1.0f, 1.0f, 1.0f);  // boxes: no vertex colour (attribute 4 not enabled)

  // Meshes: interleaved position, normal, texture coordinates and colour (11 floats), indexed.
  glGenVertexArrays(1, &g.mesh_vao);
  glBindVertexArray(g.mesh_vao);
  glGenBuffers(1, &g.mesh_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, g.mesh_vbo);
  glGenBuffers(1, &g.mesh_ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.mesh_ebo);
  const GLuint mesh_locations[4] = {0, 1, 2, 4};
  const int mesh_sizes[4] = {3, 3, 2, 3};
  offset = 0;
  for (int a = 0; a < 4; ++a) {
    glEnableVertexAttribArray(mesh_locations[a]);
    glVertexAttribPointer(mesh_locations[a], mesh_sizes[a], GL_FLOAT, GL_FALSE, 11 * sizeof(float),
                          reinterpret_cast<const void*>(offset * sizeof(float)));
    offset += static_cast<size_t>(mesh_sizes[a]);
  }
  glVertexAttrib2f(3, 0.0f, 0.0f);
  glBindVertexArray(g.vao);

  glGenFramebuffers(1, &g.fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, g.fbo);
  glGenTextures(3, g.targets.data());
  const GLenum formats[3][3] = {{GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE},
                                {GL_R32F, GL_RED, GL_FLOAT},
                                {GL_RG16UI, GL_RG_INTEGER, GL_UNSIGNED_SHORT}};
  for (int i = 0; i < 3; ++i) {
    glBindTexture(GL_TEXTURE_2D, g.targets[static_cast<size_t>(i)]);
    glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(formats[i][0]), width, height, 0,
                 formats[i][1], formats[i][2], nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(i),
                           GL_TEXTURE_2D, g.targets[static_cast<size_t>(i)], 0);
  }
  glGenRenderbuffers(1, &g.targets[3]);
  glBindRenderbuffer(GL_RENDERBUFFER, g.targets[3]);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, g.targets[3]);
  const GLenum draw[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
  glDrawBuffers(3, draw);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    throw std::runtime_error("synth renderer: framebuffer incomplete");
  }

  // Textures: mipmapped, trilinear, repeating. No anisotropic filtering: in llvmpipe it made a
  // 640x480 frame ~6x slower (206 vs 32 ms measured), far from the 20 frames/s budget.
  for (const Texture& t : texture_set.textures()) {
    GLuint id = 0;
    glGenTextures(1, &id);
    glBindTexture(GL_TEXTURE_2D, id);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    MOSLAM_CHECK(t.rgb.isContinuous() && t.rgb.type() == CV_8UC3);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, t.rgb.cols, t.rgb.rows, 0, GL_RGB, GL_UNSIGNED_BYTE,
                 t.rgb.data);
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_MIRRORED_REPEAT);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_MIRRORED_REPEAT);
    g.textures.push_back(id);
  }
  {
    const unsigned char white[4 * 4 * 3] = {
        255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255,
        255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255,
        255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255};
    glGenTextures(1, &g.white);
    glBindTexture(GL_TEXTURE_2D, g.white);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, 4, 4, 0, GL_RGB, GL_UNSIGNED_BYTE, white);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    const cv::Mat cloth = MakeFabricTexture(128);
    glGenTextures(1, &g.fabric);
    glBindTexture(GL_TEXTURE_2D, g.fabric);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, cloth.cols, cloth.rows, 0, GL_RGB, GL_UNSIGNED_BYTE,
                 cloth.data);
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_MIRRORED_REPEAT);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_MIRRORED_REPEAT);
  }
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);  // rooms are seen from inside, objects from outside
  glViewport(0, 0, width, height);
  g.ids.create(height, width, CV_16UC2);
  if (glGetError() != GL_NO_ERROR) throw std::runtime_error("synth renderer: GL set-up error");
  spdlog::debug("synth renderer: {}", RendererName());
}

Renderer::~Renderer() {
  if (impl_ && impl_->context != nullptr) OSMesaDestroyContext(impl_->context);
}

int Renderer::width() const { return impl_->width; }
int Renderer::height() const { return impl_->height; }

std::string Renderer::RendererName() const {
  const auto* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return std::string(name ? name : "?") + " " + (version ? version : "?");
}

void Renderer::Render(const std::vector<Box>& boxes, const camera::PinholeOptions& camera,
                      const geometry::SE3& T_cam_world, const Lighting& lighting,
                      RenderOutput* out) {
  Render(boxes, {}, camera, T_cam_world, lighting, out);
}

void Renderer::DrawMeshes(const std::vector<Mesh>& meshes) {
  Impl& g = *impl_;
  glUniform1i(g.u_mesh, 1);
  glUniform1f(g.u_tint, 1.0f);
  glBindVertexArray(g.mesh_vao);
  for (const Mesh& mesh : meshes) {
    g.mesh_data.resize(mesh.vertices.size() * 11);
    float* d = g.mesh_data.data();
    for (const MeshVertex& v : mesh.vertices) {
      d = std::copy(v.p.data(), v.p.data() + 3, d);
      d = std::copy(v.n.data(), v.n.data() + 3, d);
      d = std::copy(v.uv.data(), v.uv.data() + 2, d);
      d = std::copy(v.colour.data(), v.colour.data() + 3, d);
    }
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(g.mesh_data.size() * sizeof(float)),
                 g.mesh_data.data(), GL_STREAM_DRAW);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                 static_cast<GLsizeiptr>(mesh.indices.size() * sizeof(uint32_t)),
                 mesh.indices.data(), GL_STREAM_DRAW);
    glUniform2ui(g.u_label, mesh.class_id, mesh.instance);
    for (const MeshPart& part : mesh.parts) {
      MOSLAM_CHECK(part.texture >= -2 && part.texture < static_cast<int>(g.textures.size()));
      MOSLAM_CHECK(part.first + part.count <= mesh.indices.size());
      const GLuint texture = part.texture == -2   ? g.fabric
                             : part.texture == -1 ? g.white
                                                  : g.textures[static_cast<size_t>(part.texture)];
      glBindTexture(GL_TEXTURE_2D, texture);
      glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(part.count), GL_UNSIGNED_INT,
                     reinterpret_cast<const void*>(part.first * sizeof(uint32_t)));
    }
  }
  glBindVertexArray(g.vao);
  glUniform1i(g.u_mesh, 0);
}

void Renderer::Render(const std::vector<Box>& boxes, const std::vector<Mesh>& meshes,
                      const camera::PinholeOptions& camera, const geometry::SE3& T_cam_world,
                      const Lighting& lighting, RenderOutput* out) {
  Impl& g = *impl_;
  MOSLAM_CHECK(camera.width == g.width && camera.height == g.height)
      << "camera " << camera.width << "x" << camera.height << " vs renderer " << g.width << "x"
      << g.height;
  if (OSMesaGetCurrentContext() != g.context) {
    OSMesaMakeCurrent(g.context, g.dummy.data(), GL_UNSIGNED_BYTE, 16, 16);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, g.fbo);
  const float sky[4] = {static_cast<float>(lighting.sky_rgb.x()),
                        static_cast<float>(lighting.sky_rgb.y()),
                        static_cast<float>(lighting.sky_rgb.z()), 1.0f};
  const float zero_f[4] = {0, 0, 0, 0};
  const GLuint zero_u[4] = {0, 0, 0, 0};
  glClearBufferfv(GL_COLOR, 0, sky);
  glClearBufferfv(GL_COLOR, 1, zero_f);
  glClearBufferuiv(GL_COLOR, 2, zero_u);
  glClear(GL_DEPTH_BUFFER_BIT);

  glUseProgram(g.program);
  glBindVertexArray(g.vao);
  const auto projection = ToGl(Projection(camera, 0.05, 300.0));
  const auto view = ToGl(T_cam_world.Matrix());
  glUniformMatrix4fv(g.u_projection, 1, GL_FALSE, projection.data());
  glUniformMatrix4fv(g.u_view, 1, GL_FALSE, view.data());
  const Eigen::Vector3d l = lighting.direction_world.normalized();
  glUniform3f(g.u_light, static_cast<float>(l.x()), static_cast<float>(l.y()),
              static_cast<float>(l.z()));
  glUniform1f(g.u_ambient, lighting.ambient);
  glUniform1f(g.u_diffuse, lighting.diffuse);
  glActiveTexture(GL_TEXTURE0);
  // People first: they are in front of most of the room.
  DrawMeshes(meshes);
  // Front to back, large boxes (walls, floor, road) last: llvmpipe tests depth before shading, so
  // hidden surfaces drawn later cost little. Order does not change the result (depth test, opaque
  // boxes; ties are resolved by the stable order).
  const Eigen::Vector3d eye = T_cam_world.Inverse().translation();
  std::vector<std::pair<double, size_t>> order(boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i) {
    const double big = boxes[i].half.maxCoeff() > 1.5 ? 1e3 : 0.0;
    order[i] = {big + (boxes[i].T_world_box.translation() - eye).norm(), i};
  }
  std::stable_sort(order.begin(), order.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [key, index] : order) {
    const Box& b = boxes[index];
    MOSLAM_CHECK(b.texture >= 0 && b.texture < static_cast<int>(g.textures.size()));
    Eigen::Matrix4d model = b.T_world_box.Matrix();
    model.block<3, 3>(0, 0) = model.block<3, 3>(0, 0) * b.half.asDiagonal();
    const auto m = ToGl(model);
    glUniformMatrix4fv(g.u_model, 1, GL_FALSE, m.data());
    glUniform3f(g.u_half, static_cast<float>(b.half.x()), static_cast<float>(b.half.y()),
                static_cast<float>(b.half.z()));
    glUniform1f(g.u_tile, static_cast<float>(b.tile_m));
    glUniform2f(g.u_offset, static_cast<float>(b.uv_offset.x()),
                static_cast<float>(b.uv_offset.y()));
    glUniform1f(g.u_tint, b.tint);
    glUniform2ui(g.u_label, b.class_id, b.instance);
    glBindTexture(GL_TEXTURE_2D, g.textures[static_cast<size_t>(b.texture)]);
    glDrawArrays(GL_TRIANGLES, 0, 36);
  }

  out->rgb.create(g.height, g.width, CV_8UC3);
  out->depth.create(g.height, g.width, CV_32FC1);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glReadPixels(0, 0, g.width, g.height, GL_RGB, GL_UNSIGNED_BYTE, out->rgb.data);
  glReadBuffer(GL_COLOR_ATTACHMENT1);
  glReadPixels(0, 0, g.width, g.height, GL_RED, GL_FLOAT, out->depth.data);
  glReadBuffer(GL_COLOR_ATTACHMENT2);
  glReadPixels(0, 0, g.width, g.height, GL_RG_INTEGER, GL_UNSIGNED_SHORT, g.ids.data);
  out->class_id.create(g.height, g.width, CV_8UC1);
  out->instance.create(g.height, g.width, CV_16UC1);
  for (int y = 0; y < g.height; ++y) {
    const auto* in = g.ids.ptr<cv::Vec2w>(y);
    auto* cls = out->class_id.ptr<uint8_t>(y);
    auto* inst = out->instance.ptr<uint16_t>(y);
    for (int x = 0; x < g.width; ++x) {
      cls[x] = static_cast<uint8_t>(in[x][0]);
      inst[x] = in[x][1];
    }
  }
  MOSLAM_CHECK(glGetError() == GL_NO_ERROR) << "GL error while rendering";
}

}  // namespace moslam::synth
