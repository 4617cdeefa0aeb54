#version 330 core
// Fragment shader for the stick figure: Lambert diffuse + a small Blinn-Phong highlight +
// ambient, from the same uniforms pyrender sets for its PBR shader (which costs several
// times more per pixel on a CPU rasteriser). Output is gamma-encoded like pyrender's.
#define MAX_LIGHTS 4   // the uniform array's size (pyrender sets it); one light is drawn

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
    // The one key light renderers.scene.FigureRenderer adds, written out rather than looped over: llvmpipe
    // runs a loop over a uniform count with per-pixel masks, and the loop was a quarter of a mannequin frame's
    // CPU at 640x480 with 4x MSAA (12.6 -> 9.1 ms, the same pixels). Further lights would be ignored.
    if (n_directional_lights > 0) {
        vec3 l = normalize(-directional_lights[0].direction);
        vec3 radiance = directional_lights[0].color * directional_lights[0].intensity;
        float ndotl = max(dot(n, l), 0.0);
        vec3 h = normalize(l + v);
        float spec = ndotl > 0.0 ? pow(max(dot(n, h), 0.0), 40.0) : 0.0;
        color += radiance * (base * ndotl * INV_PI + 0.04 * spec);
    }
    out_color = vec4(pow(clamp(color, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
