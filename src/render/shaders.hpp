// GLSL 4.50 sources of the renderer's programs. Lighting is fixed so images are deterministic
// and comparable between strategies: one directional light plus ambient, two-sided (meshes from
// the wild have inconsistent winding and nothing is culled, so a normal is turned towards the
// eye rather than trusted to match the winding).
#pragma once

namespace cellwalk::render {

// Attribute and uniform locations shared by the C++ side and the sources below.
constexpr unsigned kPositionAttribute = 0;
constexpr unsigned kNormalAttribute = 1;
constexpr unsigned kColorAttribute = 2;
constexpr int kViewProjectionUniform = 0;
constexpr int kObjectIdUniform = 1;
constexpr int kEyePositionUniform = 2;

constexpr const char* kMeshVertexShader = R"(#version 450 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_color;
layout(location = 0) uniform mat4 u_view_projection;
out vec3 v_position;
out vec3 v_normal;
out vec4 v_color;
void main() {
  gl_Position = u_view_projection * vec4(a_position, 1.0);
  v_position = a_position;
  v_normal = a_normal;
  v_color = a_color;
}
)";

constexpr const char* kMeshFragmentShader = R"(#version 450 core
layout(location = 1) uniform uint u_object_id;  // object id + 1; 0 is the background
layout(location = 2) uniform vec3 u_eye_position;
in vec3 v_position;
in vec3 v_normal;
in vec4 v_color;
layout(location = 0) out vec4 o_color;
layout(location = 1) out uint o_id;
const vec3 kLightDirection = normalize(vec3(0.4, 1.0, 0.3));  // towards the light, world space
const float kAmbient = 0.35;
void main() {
  float length_squared = dot(v_normal, v_normal);
  vec3 n = length_squared > 0.0 ? v_normal * inversesqrt(length_squared) : vec3(0.0);
  if (dot(n, u_eye_position - v_position) < 0.0) n = -n;
  float light = kAmbient + (1.0 - kAmbient) * max(dot(n, kLightDirection), 0.0);
  o_color = vec4(v_color.rgb * light, 1.0);
  o_id = u_object_id;
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

}  // namespace cellwalk::render
