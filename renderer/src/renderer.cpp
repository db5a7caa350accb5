#include "inhand/renderer/renderer.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/osmesa.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

#include "inhand/core/error.hpp"
#include "inhand/renderer/osmesa.hpp"
#include "inhand/sessions/image_io.hpp"

namespace inhand {

namespace {

// Copies `row` (a whole row's values) into every element of a width x height image outside
// `inside`: the rows above and below it whole, the columns left and right of it in its rows.
template <typename T>
void FillOutside(T* data, int width, int height, const PixelRect& inside, const T* row) {
  for (int y = 0; y < height; ++y) {
    T* out = data + std::size_t(y) * width;
    if (y < inside.y0 || y >= inside.y1 || inside.empty()) {
      std::copy_n(row, width, out);
    } else {
      std::copy_n(row, inside.x0, out);
      std::copy(row + inside.x1, row + width, out + inside.x1);
    }
  }
}

}  // namespace

Eigen::Matrix4d ProjectionMatrix(const Intrinsics& K, double n, double f) {
  const double W = K.width, H = K.height;
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  // NDC x = 2 (u + 0.5) / W - 1 and NDC y = 2 (v + 0.5) / H - 1, with w = z (camera z forward).
  // Image rows thus map to GL rows in reading order: glReadPixels returns the top row first.
  P(0, 0) = 2.0 * K.fx / W;
  P(0, 2) = 2.0 * (K.cx + 0.5) / W - 1.0;
  P(1, 1) = 2.0 * K.fy / H;
  P(1, 2) = 2.0 * (K.cy + 0.5) / H - 1.0;
  P(2, 2) = (f + n) / (f - n);
  P(2, 3) = -2.0 * f * n / (f - n);
  P(3, 2) = 1.0;
  return P;
}

namespace {

constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
uniform mat4 u_model_cam;
uniform mat4 u_proj;
out vec3 v_pos_c;
out vec3 v_normal_c;
out vec2 v_uv;
void main() {
  vec4 pc = u_model_cam * vec4(a_pos, 1.0);
  v_pos_c = pc.xyz;
  v_normal_c = mat3(u_model_cam) * a_normal;
  v_uv = a_uv;
  gl_Position = u_proj * pc;
}
)";

constexpr const char* kFragmentShader = R"(#version 330 core
in vec3 v_pos_c;
in vec3 v_normal_c;
in vec2 v_uv;
uniform vec4 u_color;
uniform int u_use_texture;
uniform sampler2D u_tex;
uniform uint u_label;
uniform int u_unlit;
uniform vec3 u_light_c;
layout(location = 0) out vec4 o_color;
layout(location = 1) out uint o_label;
layout(location = 2) out float o_depth;
void main() {
  vec4 base = u_color;
  if (u_use_texture != 0) base *= texture(u_tex, vec2(v_uv.x, 1.0 - v_uv.y));
  vec3 c = base.rgb;
  if (u_unlit == 0) {
    vec3 n = normalize(v_normal_c);
    vec3 view = normalize(-v_pos_c);
    if (dot(n, view) < 0.0) n = -n;
    float key = max(dot(n, u_light_c), 0.0);
    float head = max(dot(n, view), 0.0);
    vec3 h = normalize(u_light_c + view);
    float spec = pow(max(dot(n, h), 0.0), 32.0) * 0.12;
    c = base.rgb * (0.28 + 0.42 * key + 0.38 * head) + vec3(spec);
  }
  o_color = vec4(clamp(c, 0.0, 1.0), base.a);
  o_label = u_label;
  o_depth = v_pos_c.z;
}
)";

// The GL functions the renderer calls, from OSMesa's contexts (osmesa.hpp), with the headers'
// own types.
#define INHAND_RENDERER_GL_FUNCTIONS(X) \
  X(ActiveTexture)                      \
  X(AttachShader)                       \
  X(BindBuffer)                         \
  X(BindFramebuffer)                    \
  X(BindRenderbuffer)                   \
  X(BindTexture)                        \
  X(BindVertexArray)                    \
  X(BlendFunci)                         \
  X(BufferData)                         \
  X(CheckFramebufferStatus)             \
  X(Clear)                              \
  X(ClearBufferfv)                      \
  X(ClearBufferuiv)                     \
  X(ColorMaski)                         \
  X(CompileShader)                      \
  X(CreateProgram)                      \
  X(CreateShader)                       \
  X(DeleteFramebuffers)                 \
  X(DeleteRenderbuffers)                \
  X(DeleteShader)                       \
  X(DepthFunc)                          \
  X(DepthMask)                          \
  X(Disable)                            \
  X(Disablei)                           \
  X(DrawBuffers)                        \
  X(DrawElements)                       \
  X(Enable)                             \
  X(EnableVertexAttribArray)            \
  X(Enablei)                            \
  X(FramebufferRenderbuffer)            \
  X(GenBuffers)                         \
  X(GenFramebuffers)                    \
  X(GenRenderbuffers)                   \
  X(GenTextures)                        \
  X(GenVertexArrays)                    \
  X(GenerateMipmap)                     \
  X(GetProgramiv)                       \
  X(GetShaderInfoLog)                   \
  X(GetShaderiv)                        \
  X(GetString)                          \
  X(GetUniformLocation)                 \
  X(LinkProgram)                        \
  X(LogicOp)                            \
  X(PixelStorei)                        \
  X(ReadBuffer)                         \
  X(ReadPixels)                         \
  X(RenderbufferStorage)                \
  X(Scissor)                            \
  X(ShaderSource)                       \
  X(TexImage2D)                         \
  X(TexParameteri)                      \
  X(Uniform1i)                          \
  X(Uniform1ui)                         \
  X(Uniform3f)                          \
  X(Uniform4f)                          \
  X(UniformMatrix4fv)                   \
  X(UseProgram)                         \
  X(VertexAttribPointer)                \
  X(Viewport)

struct GlApi {
#define INHAND_GL_MEMBER(name) decltype(&::gl##name) name = nullptr;
  INHAND_RENDERER_GL_FUNCTIONS(INHAND_GL_MEMBER)
#undef INHAND_GL_MEMBER
  decltype(&::OSMesaCreateContextAttribs) CreateContextAttribs = nullptr;
  decltype(&::OSMesaMakeCurrent) MakeCurrent = nullptr;
  decltype(&::OSMesaDestroyContext) DestroyContext = nullptr;
};

GlApi LoadGl() {
  GlApi api;
#define INHAND_GL_LOAD(name) \
  api.name = reinterpret_cast<decltype(api.name)>(OsMesaFunction("gl" #name));
  INHAND_RENDERER_GL_FUNCTIONS(INHAND_GL_LOAD)
#undef INHAND_GL_LOAD
  api.CreateContextAttribs = reinterpret_cast<decltype(api.CreateContextAttribs)>(
      OsMesaFunction("OSMesaCreateContextAttribs"));
  api.MakeCurrent =
      reinterpret_cast<decltype(api.MakeCurrent)>(OsMesaFunction("OSMesaMakeCurrent"));
  api.DestroyContext =
      reinterpret_cast<decltype(api.DestroyContext)>(OsMesaFunction("OSMesaDestroyContext"));
  return api;
}

// Loaded once per process, on the first renderer.
const GlApi& Gl() {
  static const GlApi api = LoadGl();
  return api;
}

GLuint Compile(const GlApi& gl, GLenum type, const char* source) {
  const GLuint s = gl.CreateShader(type);
  gl.ShaderSource(s, 1, &source, nullptr);
  gl.CompileShader(s);
  GLint ok = 0;
  gl.GetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048];
    gl.GetShaderInfoLog(s, sizeof(log), nullptr, log);
    throw std::runtime_error(std::string("renderer: shader compilation failed: ") + log);
  }
  return s;
}

struct GpuMesh {
  GLuint vao = 0, vbo = 0, ebo = 0;
  GLsizei count = 0;
  Eigen::Vector4d rgba;
  GLuint texture = 0;
  Aabb bounds;
};

}  // namespace

struct Renderer::Impl {
  const GlApi& gl = Gl();
  OSMesaContext ctx = nullptr;
  std::vector<std::uint8_t> default_buffer = std::vector<std::uint8_t>(16 * 16 * 4);
  GLuint program = 0;
  GLint u_model_cam = -1, u_proj = -1, u_color = -1, u_use_texture = -1, u_tex = -1, u_label = -1,
        u_unlit = -1, u_light = -1;
  std::vector<GpuMesh> meshes;
  std::map<std::string, GLuint> textures;
  GLuint fbo = 0, rb_color = 0, rb_label = 0, rb_depthf = 0, rb_zbuffer = 0;
  int fb_w = 0, fb_h = 0;

  void MakeCurrent() {
    if (!gl.MakeCurrent(ctx, default_buffer.data(), GL_UNSIGNED_BYTE, 16, 16))
      throw std::runtime_error("renderer: OSMesaMakeCurrent failed");
  }

  void EnsureFramebuffer(int w, int h) {
    if (fbo && w == fb_w && h == fb_h) return;
    if (fbo) {
      gl.DeleteFramebuffers(1, &fbo);
      const GLuint rbs[4] = {rb_color, rb_label, rb_depthf, rb_zbuffer};
      gl.DeleteRenderbuffers(4, rbs);
    }
    gl.GenFramebuffers(1, &fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    const auto make_rb = [&](GLenum format, GLenum attachment) {
      GLuint rb;
      gl.GenRenderbuffers(1, &rb);
      gl.BindRenderbuffer(GL_RENDERBUFFER, rb);
      gl.RenderbufferStorage(GL_RENDERBUFFER, format, w, h);
      gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, attachment, GL_RENDERBUFFER, rb);
      return rb;
    };
    rb_color = make_rb(GL_RGBA8, GL_COLOR_ATTACHMENT0);
    rb_label = make_rb(GL_R16UI, GL_COLOR_ATTACHMENT1);
    rb_depthf = make_rb(GL_R32F, GL_COLOR_ATTACHMENT2);
    rb_zbuffer = make_rb(GL_DEPTH_COMPONENT24, GL_DEPTH_ATTACHMENT);
    if (gl.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw std::runtime_error("renderer: framebuffer incomplete");
    fb_w = w;
    fb_h = h;
  }

  GLuint Texture(const Material& m) {
    std::string key = m.texture_file;
    if (key.empty()) {  // embedded: keyed by content (FNV-1a)
      std::uint64_t h = 1469598103934665603ULL;
      for (std::uint8_t byte : m.texture_blob) h = (h ^ byte) * 1099511628211ULL;
      key = "blob:" + std::to_string(h) + ":" + std::to_string(m.texture_blob.size());
    }
    if (auto it = textures.find(key); it != textures.end()) return it->second;
    const Image8 rgb = !m.texture_file.empty()
                           ? ReadImage(m.texture_file)
                           : DecodeImage(m.texture_blob.data(), m.texture_blob.size(),
                                         "embedded texture of material '" + m.name + "'");
    GLuint tex;
    gl.GenTextures(1, &tex);
    gl.BindTexture(GL_TEXTURE_2D, tex);
    gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, rgb.width, rgb.height, 0, GL_RGB, GL_UNSIGNED_BYTE,
                  rgb.data.data());
    gl.GenerateMipmap(GL_TEXTURE_2D);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    textures.emplace(key, tex);
    return tex;
  }
};

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {
  const int attribs[] = {OSMESA_FORMAT,
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
  impl_->ctx = impl_->gl.CreateContextAttribs(attribs, nullptr);
  if (impl_->ctx == nullptr)
    throw std::runtime_error("renderer: cannot create an OSMesa OpenGL 3.3 core context");
  impl_->MakeCurrent();
  Impl& r = *impl_;
  const GlApi& gl = r.gl;
  const GLuint vs = Compile(gl, GL_VERTEX_SHADER, kVertexShader);
  const GLuint fs = Compile(gl, GL_FRAGMENT_SHADER, kFragmentShader);
  r.program = gl.CreateProgram();
  gl.AttachShader(r.program, vs);
  gl.AttachShader(r.program, fs);
  gl.LinkProgram(r.program);
  GLint ok = 0;
  gl.GetProgramiv(r.program, GL_LINK_STATUS, &ok);
  if (!ok) throw std::runtime_error("renderer: shader program does not link");
  gl.DeleteShader(vs);
  gl.DeleteShader(fs);
  r.u_model_cam = gl.GetUniformLocation(r.program, "u_model_cam");
  r.u_proj = gl.GetUniformLocation(r.program, "u_proj");
  r.u_color = gl.GetUniformLocation(r.program, "u_color");
  r.u_use_texture = gl.GetUniformLocation(r.program, "u_use_texture");
  r.u_tex = gl.GetUniformLocation(r.program, "u_tex");
  r.u_label = gl.GetUniformLocation(r.program, "u_label");
  r.u_unlit = gl.GetUniformLocation(r.program, "u_unlit");
  r.u_light = gl.GetUniformLocation(r.program, "u_light_c");
}

Renderer::~Renderer() {
  if (impl_->ctx) impl_->gl.DestroyContext(impl_->ctx);
}

std::string Renderer::Description() const {
  impl_->MakeCurrent();
  const GlApi& gl = impl_->gl;
  const auto* renderer = reinterpret_cast<const char*>(gl.GetString(GL_RENDERER));
  const auto* version = reinterpret_cast<const char*>(gl.GetString(GL_VERSION));
  return std::string("OSMesa: ") + (renderer ? renderer : "?") + ", OpenGL " +
         (version ? version : "?");
}

std::size_t Renderer::num_meshes() const { return impl_->meshes.size(); }

int Renderer::AddMesh(const TriangleMesh& mesh) {
  impl_->MakeCurrent();
  const GlApi& gl = impl_->gl;
  GpuMesh g;
  g.rgba = mesh.material.rgba;
  g.bounds = mesh.Bounds();
  std::vector<float> data;
  data.reserve(mesh.vertices.size() * 8);
  const bool has_normals = mesh.normals.size() == mesh.vertices.size();
  const bool has_uv = mesh.uvs.size() == mesh.vertices.size();
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3& v = mesh.vertices[i];
    const Vec3 n = has_normals ? mesh.normals[i] : Vec3::UnitZ();
    const Vec2 uv = has_uv ? mesh.uvs[i] : Vec2::Zero();
    for (double x : {v.x(), v.y(), v.z(), n.x(), n.y(), n.z(), uv.x(), uv.y()})
      data.push_back(static_cast<float>(x));
  }
  std::vector<std::uint32_t> indices;
  indices.reserve(mesh.triangles.size() * 3);
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) indices.push_back(static_cast<std::uint32_t>(t[k]));
  gl.GenVertexArrays(1, &g.vao);
  gl.BindVertexArray(g.vao);
  gl.GenBuffers(1, &g.vbo);
  gl.BindBuffer(GL_ARRAY_BUFFER, g.vbo);
  gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data(),
                GL_STATIC_DRAW);
  gl.GenBuffers(1, &g.ebo);
  gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
  gl.BufferData(GL_ELEMENT_ARRAY_BUFFER,
                static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)), indices.data(),
                GL_STATIC_DRAW);
  const GLsizei stride = 8 * sizeof(float);
  gl.EnableVertexAttribArray(0);
  gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, nullptr);
  gl.EnableVertexAttribArray(1);
  gl.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride,
                         reinterpret_cast<void*>(3 * sizeof(float)));
  gl.EnableVertexAttribArray(2);
  gl.VertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, stride,
                         reinterpret_cast<void*>(6 * sizeof(float)));
  gl.BindVertexArray(0);
  g.count = static_cast<GLsizei>(indices.size());
  if (mesh.material.HasTexture() && has_uv) g.texture = impl_->Texture(mesh.material);
  impl_->meshes.push_back(g);
  return static_cast<int>(impl_->meshes.size()) - 1;
}

void Renderer::Render(const Scene& scene, RenderOutput& out, bool with_depth_and_labels) {
  Impl& r = *impl_;
  const GlApi& gl = r.gl;
  r.MakeCurrent();
  const int W = scene.K.width, H = scene.K.height;
  r.EnsureFramebuffer(W, H);
  gl.BindFramebuffer(GL_FRAMEBUFFER, r.fbo);
  const GLenum buffers[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
  gl.DrawBuffers(3, buffers);
  gl.Viewport(0, 0, W, H);
  gl.ColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl.ColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl.ColorMaski(2, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl.DepthMask(GL_TRUE);
  const float bg[4] = {static_cast<float>(scene.background.x()),
                       static_cast<float>(scene.background.y()),
                       static_cast<float>(scene.background.z()), 1.0f};
  const GLuint zero_label[4] = {0, 0, 0, 0};
  const float zero_depth[4] = {0, 0, 0, 0};
  // A region: cleared, drawn and read back only there; elsewhere the background's colour as GL
  // stores it, cleared into one pixel outside the region and read from it.
  const PixelRect region =
      scene.region.empty() ? PixelRect{0, 0, W, H} : scene.region.ClippedTo(W, H);
  const bool partial = region.width() != W || region.height() != H;
  const bool outside_at_origin = region.x0 > 0 || region.y0 > 0;  // else the last pixel is out
  const int outside_x = outside_at_origin ? 0 : W - 1, outside_y = outside_at_origin ? 0 : H - 1;
  if (partial) {
    gl.Enable(GL_SCISSOR_TEST);
    gl.Scissor(outside_x, outside_y, 1, 1);
    gl.ClearBufferfv(GL_COLOR, 0, bg);
    gl.Scissor(region.x0, region.y0, region.width(), region.height());
  }
  gl.ClearBufferfv(GL_COLOR, 0, bg);
  gl.ClearBufferuiv(GL_COLOR, 1, zero_label);
  gl.ClearBufferfv(GL_COLOR, 2, zero_depth);
  gl.Clear(GL_DEPTH_BUFFER_BIT);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LESS);
  gl.Disable(GL_CULL_FACE);
  gl.UseProgram(r.program);

  const Eigen::Matrix4f proj = ProjectionMatrix(scene.K, scene.near, scene.far).cast<float>();
  gl.UniformMatrix4fv(r.u_proj, 1, GL_FALSE, proj.data());
  const Eigen::Vector3f light =
      Eigen::Vector3f(-0.35f, -0.6f, -0.7f).normalized();  // above-left of the camera
  gl.Uniform3f(r.u_light, light.x(), light.y(), light.z());
  gl.Uniform1i(r.u_tex, 0);
  const Transform T_CP = scene.T_PC.inverse();

  // Opaque first; translucent sorted back to front by their centre's depth.
  std::vector<std::pair<double, const SceneItem*>> translucent;
  const auto draw = [&](const SceneItem& item) {
    const GpuMesh& g = r.meshes.at(static_cast<std::size_t>(item.mesh));
    const Eigen::Matrix4f model_cam = (T_CP * item.T_PM).matrix().cast<float>();
    gl.UniformMatrix4fv(r.u_model_cam, 1, GL_FALSE, model_cam.data());
    Eigen::Vector4d c = item.rgba ? *item.rgba : g.rgba;
    c[3] *= item.opacity;
    gl.Uniform4f(r.u_color, static_cast<float>(c[0]), static_cast<float>(c[1]),
                 static_cast<float>(c[2]), static_cast<float>(c[3]));
    gl.Uniform1i(r.u_use_texture, g.texture && !item.rgba ? 1 : 0);
    gl.ActiveTexture(GL_TEXTURE0);
    gl.BindTexture(GL_TEXTURE_2D, g.texture);
    gl.Uniform1ui(r.u_label, item.label);
    gl.Uniform1i(r.u_unlit, item.unlit ? 1 : 0);
    gl.BindVertexArray(g.vao);
    gl.DrawElements(GL_TRIANGLES, g.count, GL_UNSIGNED_INT, nullptr);
  };
  gl.Disablei(GL_BLEND, 0);
  for (const SceneItem& item : scene.items) {
    const GpuMesh& g = r.meshes.at(static_cast<std::size_t>(item.mesh));
    const double alpha = (item.rgba ? (*item.rgba)[3] : g.rgba[3]) * item.opacity;
    if (alpha < 0.999) {
      translucent.emplace_back((T_CP * item.T_PM * g.bounds.Center()).z(), &item);
      continue;
    }
    draw(item);
  }
  if (!translucent.empty()) {
    std::stable_sort(translucent.begin(), translucent.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    gl.Enablei(GL_BLEND, 0);
    gl.BlendFunci(0, GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    gl.ColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    gl.ColorMaski(2, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    gl.DepthMask(GL_FALSE);
    for (const auto& [depth, item] : translucent) draw(*item);
    gl.DepthMask(GL_TRUE);
    gl.Disablei(GL_BLEND, 0);
  }
  gl.BindVertexArray(0);

  // Read back straight into the output: the projection put the top image row first. Outside a
  // region, the background.
  out.width = W;
  out.height = H;
  if (out.colour.width != W || out.colour.height != H || out.colour.channels != 3)
    out.colour = Image8(W, H, 3);
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl.PixelStorei(GL_PACK_ROW_LENGTH, W);
  const auto read = [&](GLenum buffer, GLenum format, GLenum type, std::size_t bytes, void* data) {
    gl.ReadBuffer(buffer);
    if (region.empty()) return;
    gl.ReadPixels(
        region.x0, region.y0, region.width(), region.height(), format, type,
        static_cast<std::uint8_t*>(data) + (std::size_t(region.y0) * W + region.x0) * bytes);
  };
  if (partial) {
    std::uint8_t background[3];
    gl.ReadBuffer(GL_COLOR_ATTACHMENT0);
    gl.ReadPixels(outside_x, outside_y, 1, 1, GL_RGB, GL_UNSIGNED_BYTE, background);
    std::vector<std::uint8_t> row(std::size_t(W) * 3);
    for (std::size_t i = 0; i < row.size(); i += 3) std::copy_n(background, 3, &row[i]);
    FillOutside(out.colour.data.data(), W * 3, H,
                PixelRect{region.x0 * 3, region.y0, region.x1 * 3, region.y1}, row.data());
  }
  read(GL_COLOR_ATTACHMENT0, GL_RGB, GL_UNSIGNED_BYTE, 3, out.colour.data.data());
  if (with_depth_and_labels) {
    out.depth.resize(std::size_t(W) * H);
    out.label.resize(std::size_t(W) * H);
    if (partial) {
      const std::vector<float> inf(std::size_t(W), std::numeric_limits<float>::infinity());
      const std::vector<std::uint16_t> none(std::size_t(W), 0);
      FillOutside(out.depth.data(), W, H, region, inf.data());
      FillOutside(out.label.data(), W, H, region, none.data());
    }
    read(GL_COLOR_ATTACHMENT2, GL_RED, GL_FLOAT, sizeof(float), out.depth.data());
    for (int y = region.y0; y < region.y1; ++y)
      for (int x = region.x0; x < region.x1; ++x) {
        float& z = out.depth[std::size_t(y) * W + x];
        if (!(z > 0.0f)) z = std::numeric_limits<float>::infinity();
      }
    read(GL_COLOR_ATTACHMENT1, GL_RED_INTEGER, GL_UNSIGNED_SHORT, sizeof(std::uint16_t),
         out.label.data());
  } else {
    out.depth.clear();
    out.label.clear();
  }
  gl.PixelStorei(GL_PACK_ROW_LENGTH, 0);
  if (partial) gl.Disable(GL_SCISSOR_TEST);
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
}

void Renderer::RenderMasks(const Scene& scene, std::vector<std::uint16_t>& bits) {
  Impl& r = *impl_;
  const GlApi& gl = r.gl;
  r.MakeCurrent();
  const int W = scene.K.width, H = scene.K.height;
  r.EnsureFramebuffer(W, H);
  gl.BindFramebuffer(GL_FRAMEBUFFER, r.fbo);
  const GLenum buffers[3] = {GL_NONE, GL_COLOR_ATTACHMENT1, GL_NONE};  // the labels only
  gl.DrawBuffers(3, buffers);
  gl.Viewport(0, 0, W, H);
  gl.ColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  const GLuint zero_label[4] = {0, 0, 0, 0};
  gl.ClearBufferuiv(GL_COLOR, 1, zero_label);
  gl.Disable(GL_DEPTH_TEST);
  gl.DepthMask(GL_FALSE);
  gl.Disable(GL_CULL_FACE);
  gl.Disablei(GL_BLEND, 0);
  gl.Enable(GL_COLOR_LOGIC_OP);  // integer targets: the labels are OR-ed
  gl.LogicOp(GL_OR);
  gl.UseProgram(r.program);
  const Eigen::Matrix4f proj = ProjectionMatrix(scene.K, scene.near, scene.far).cast<float>();
  gl.UniformMatrix4fv(r.u_proj, 1, GL_FALSE, proj.data());
  gl.Uniform1i(r.u_use_texture, 0);
  gl.Uniform1i(r.u_unlit, 1);
  const Transform T_CP = scene.T_PC.inverse();
  for (const SceneItem& item : scene.items) {
    const GpuMesh& g = r.meshes.at(static_cast<std::size_t>(item.mesh));
    const Eigen::Matrix4f model_cam = (T_CP * item.T_PM).matrix().cast<float>();
    gl.UniformMatrix4fv(r.u_model_cam, 1, GL_FALSE, model_cam.data());
    gl.Uniform1ui(r.u_label, item.label);
    gl.BindVertexArray(g.vao);
    gl.DrawElements(GL_TRIANGLES, g.count, GL_UNSIGNED_INT, nullptr);
  }
  gl.BindVertexArray(0);
  gl.Disable(GL_COLOR_LOGIC_OP);
  gl.DepthMask(GL_TRUE);
  gl.Enable(GL_DEPTH_TEST);
  bits.resize(std::size_t(W) * H);
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl.ReadBuffer(GL_COLOR_ATTACHMENT1);
  gl.ReadPixels(0, 0, W, H, GL_RED_INTEGER, GL_UNSIGNED_SHORT, bits.data());
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
}

}  // namespace inhand
