// GLSL 4.50 sources of the renderer's programs. Lighting is fixed so images are deterministic
// and comparable between strategies: one directional light plus ambient, two-sided (meshes from
// the wild have inconsistent winding and nothing is culled, so a normal is turned towards the
// eye rather than trusted to match the winding). The browser client draws with the same mesh and
// backdrop programs in GLSL ES (web/src/renderer.js): a change here is made there too.
#pragma once

namespace cellwalk::render {

// Attribute and uniform locations shared by the C++ side and the sources below.
constexpr unsigned kPositionAttribute = 0;
constexpr unsigned kNormalAttribute = 1;
constexpr unsigned kColorAttribute = 2;
constexpr unsigned kUvAttribute = 3;
constexpr int kViewProjectionUniform = 0;
constexpr int kObjectIdUniform = 1;
constexpr int kEyePositionUniform = 2;
constexpr int kTexturedUniform = 3;  // 1: the base colour is the colour times texture unit 0

constexpr const char* kMeshVertexShader = R"(#version 450 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_color;
layout(location = 3) in vec2 a_uv;
layout(location = 0) uniform mat4 u_view_projection;
out vec3 v_position;
out vec3 v_normal;
out vec4 v_color;
out vec2 v_uv;
void main() {
  gl_Position = u_view_projection * vec4(a_position, 1.0);
  v_position = a_position;
  v_normal = a_normal;
  v_color = a_color;
  v_uv = a_uv;
}
)";

constexpr const char* kMeshFragmentShader = R"(#version 450 core
layout(location = 1) uniform uint u_object_id;  // object id + 1; 0 is the background
layout(location = 2) uniform vec3 u_eye_position;
layout(location = 3) uniform int u_textured;
layout(binding = 0) uniform sampler2D u_texture;
in vec3 v_position;
in vec3 v_normal;
in vec4 v_color;
in vec2 v_uv;
layout(location = 0) out vec4 o_color;
layout(location = 1) out uint o_id;
const vec3 kLightDirection = normalize(vec3(0.4, 1.0, 0.3));  // towards the light, world space
const float kAmbient = 0.35;
void main() {
  float length_squared = dot(v_normal, v_normal);
  vec3 n = length_squared > 0.0 ? v_normal * inversesqrt(length_squared) : vec3(0.0);
  if (dot(n, u_eye_position - v_position) < 0.0) n = -n;
  float light = kAmbient + (1.0 - kAmbient) * max(dot(n, kLightDirection), 0.0);
  vec3 base = v_color.rgb;
  if (u_textured != 0) base *= texture(u_texture, v_uv).rgb;
  o_color = vec4(base * light, 1.0);
  o_id = u_object_id;
}
)";

// The backdrop: one full-screen triangle; each pixel's view ray picks sky or ground.
constexpr int kInverseViewProjectionUniform = 0;
constexpr int kBackdropEyeUniform = 1;
constexpr int kSkyColorUniform = 2;
constexpr int kGroundUniform = 3;  // (height, grid step, haze distance)

constexpr const char* kBackdropVertexShader = R"(#version 450 core
out vec2 v_ndc;
void main() {
  vec2 corner = vec2((gl_VertexID & 1) * 4.0 - 1.0, (gl_VertexID >> 1) * 4.0 - 1.0);
  v_ndc = corner;
  gl_Position = vec4(corner, 1.0, 1.0);
}
)";

constexpr const char* kBackdropFragmentShader = R"(#version 450 core
layout(location = 0) uniform mat4 u_inverse_view_projection;
layout(location = 1) uniform vec3 u_eye;
layout(location = 2) uniform vec3 u_sky;
layout(location = 3) uniform vec3 u_ground;
in vec2 v_ndc;
layout(location = 0) out vec4 o_color;
void main() {
  vec4 near_point = u_inverse_view_projection * vec4(v_ndc, -1.0, 1.0);
  vec4 far_point = u_inverse_view_projection * vec4(v_ndc, 1.0, 1.0);
  vec3 dir = normalize(far_point.xyz / far_point.w - near_point.xyz / near_point.w);
  float height = u_eye.y - u_ground.x;
  if (dir.y >= 0.0 || height <= 0.0) {
    vec3 zenith = vec3(0.36, 0.55, 0.85);
    o_color = vec4(mix(u_sky, zenith, sqrt(max(dir.y, 0.0))), 1.0);
    return;
  }
  vec3 ground = u_eye + dir * (height / -dir.y);
  vec2 cell = abs(fract(ground.xz / u_ground.y) - 0.5);
  float line = step(0.48, max(cell.x, cell.y));
  float haze = clamp(length(ground - u_eye) / u_ground.z, 0.0, 1.0);
  vec3 earth = mix(vec3(0.42, 0.44, 0.40), vec3(0.34, 0.36, 0.33), line);
  o_color = vec4(mix(earth, u_sky, haze), 1.0);
}
)";

// Overlays (lines, text): flat colour, no lighting; writes the colour target only.
constexpr int kOverlayMatrixUniform = 0;

constexpr const char* kOverlayVertexShader = R"(#version 450 core
layout(location = 0) in vec3 a_position;
layout(location = 2) in vec4 a_color;
layout(location = 0) uniform mat4 u_matrix;
out vec4 v_color;
void main() {
  gl_Position = u_matrix * vec4(a_position, 1.0);
  v_color = a_color;
}
)";

constexpr const char* kOverlayFragmentShader = R"(#version 450 core
in vec4 v_color;
layout(location = 0) out vec4 o_color;
void main() { o_color = v_color; }
)";

// Far faces (stratified rendering): a quad origin + s·u + t·v made in the vertex shader from the
// vertex id (a 4-vertex strip), showing an RGBA8 image and, where it has one, an id image. Texels
// with alpha < 0.5 held no far geometry: they are discarded, so the backdrop shows through.
constexpr int kFarOriginUniform = 1;
constexpr int kFarAxisUUniform = 2;
constexpr int kFarAxisVUniform = 3;
constexpr int kFarFaceIdUniform = 4;   // the face's own pixel id, used where it has no id image
constexpr int kFarHasIdsUniform = 5;

constexpr const char* kFarFaceVertexShader = R"(#version 450 core
layout(location = 0) uniform mat4 u_view_projection;
layout(location = 1) uniform vec3 u_origin;
layout(location = 2) uniform vec3 u_axis_u;
layout(location = 3) uniform vec3 u_axis_v;
out vec2 v_st;
void main() {
  vec2 st = vec2(gl_VertexID & 1, gl_VertexID >> 1);
  v_st = st;
  gl_Position = u_view_projection * vec4(u_origin + st.x * u_axis_u + st.y * u_axis_v, 1.0);
}
)";

constexpr const char* kFarFaceFragmentShader = R"(#version 450 core
layout(binding = 0) uniform sampler2D u_color;
layout(binding = 1) uniform usampler2D u_ids;
layout(location = 4) uniform uint u_face_id;
layout(location = 5) uniform int u_has_ids;
in vec2 v_st;
layout(location = 0) out vec4 o_color;
layout(location = 1) out uint o_id;
void main() {
  vec4 c = texture(u_color, v_st);
  if (c.a < 0.5) discard;
  // Empty texels are (0, 0, 0, 0): filtering across an edge mixes them in, so undo the weight.
  o_color = vec4(c.rgb / c.a, 1.0);
  ivec2 size = textureSize(u_ids, 0);
  o_id = u_has_ids != 0 ? texelFetch(u_ids, clamp(ivec2(v_st * vec2(size)), ivec2(0), size - 1), 0).r : u_face_id;
}
)";

}  // namespace cellwalk::render
