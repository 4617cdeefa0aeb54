#version 330 core
// Vertex shader for the stick figure and floor: pyrender's attribute layout, but the normal
// is transformed by the model matrix directly (our meshes are only ever placed with rigid
// transforms), sparing pyrender's per-vertex 4x4 inverse.
layout(location = 0) in vec3 position;
#ifdef NORMAL_LOC
layout(location = NORMAL_LOC) in vec3 normal;
#endif
#ifdef COLOR_0_LOC
layout(location = COLOR_0_LOC) in vec4 color_0;
#endif
layout(location = INST_M_LOC) in mat4 inst_m;

uniform mat4 M;
uniform mat4 V;
uniform mat4 P;

out vec3 frag_position;
out vec3 frag_normal;
out vec4 frag_color;

void main()
{
    mat4 W = M * inst_m;
    vec4 world = W * vec4(position, 1.0);
    gl_Position = P * V * world;
    frag_position = world.xyz;
#ifdef NORMAL_LOC
    frag_normal = mat3(W) * normal;
#else
    frag_normal = vec3(0.0, 1.0, 0.0);
#endif
#ifdef COLOR_0_LOC
    frag_color = color_0;
#else
    frag_color = vec4(1.0);
#endif
}
