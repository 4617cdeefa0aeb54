#version 330 core
// Fragment shader for the stick figure: Lambert diffuse + a small Blinn-Phong highlight +
// ambient, from the same uniforms pyrender sets for its PBR shader (which costs several
// times more per pixel on a CPU rasteriser). Output is gamma-encoded like pyrender's.
#define MAX_LIGHTS 4

struct DirectionalLight {
    vec3 direction;
    vec3 color;
    float intensity;
};
struct Material {
    vec4 base_color_factor;
};

uniform Material material;
uniform DirectionalLight directional_lights[MAX_LIGHTS];
uniform int n_directional_lights;
uniform vec3 ambient_light;
uniform vec3 cam_pos;

in vec3 frag_position;
in vec3 frag_normal;
in vec4 frag_color;

out vec4 out_color;

const float INV_PI = 0.31830988618;

void main()
{
    vec3 base = material.base_color_factor.rgb * frag_color.rgb;
    vec3 n = normalize(frag_normal);
    vec3 v = normalize(cam_pos - frag_position);
    vec3 color = ambient_light * base;
    for (int i = 0; i < n_directional_lights && i < MAX_LIGHTS; i++) {
        vec3 l = normalize(-directional_lights[i].direction);
        vec3 radiance = directional_lights[i].color * directional_lights[i].intensity;
        float ndotl = max(dot(n, l), 0.0);
        vec3 h = normalize(l + v);
        float spec = ndotl > 0.0 ? pow(max(dot(n, h), 0.0), 40.0) : 0.0;
        color += radiance * (base * ndotl * INV_PI + 0.04 * spec);
    }
    out_color = vec4(pow(clamp(color, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
