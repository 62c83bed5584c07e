"""The GLSL twin of explorer/physics/microfacet.py (shaders/lib/microfacet.glsl) against numpy."""

from __future__ import annotations

import numpy as np
import pytest

from explorer.physics import microfacet
from explorer.materials.glsl import ShaderBuilder
from explorer.gpu.context import VERTEX_SHADER
from explorer.resources import SHADER_DIR

#: float32 against float64, relative where values exceed 1e-3 (the lobe of a sharp alpha is steep).
RELATIVE = 2e-3
SIZE = 48

PROBE = """#include "lib/microfacet.glsl"
uniform float alpha;
out vec4 result;
void main() {
    float theta_i = radians(89.9) * gl_FragCoord.x / SIZE, theta_o = radians(89.9) * gl_FragCoord.y / SIZE;
    vec3 i = vec3(sin(theta_i), 0.0, cos(theta_i));
    vec3 o = vec3(-0.6 * sin(theta_o), 0.8 * sin(theta_o), cos(theta_o));
    result = vec4(microfacet_lobe(i, o, vec3(0.0, 0.0, 1.0), alpha), smith_G1(cos(theta_i), alpha),
                  ggx_D(cos(theta_o), alpha), half_vector_cosine(i, o));
}
"""


def numpy_probe(alpha: float) -> np.ndarray:
    angles = np.float32(np.radians(89.9)) * ((np.arange(SIZE, dtype=np.float32) + np.float32(0.5)) / np.float32(SIZE))
    theta_i, theta_o = np.meshgrid(angles.astype(np.float64), angles.astype(np.float64))
    i = np.stack([np.sin(theta_i), 0.0 * theta_i, np.cos(theta_i)], axis=-1)
    o = np.stack([-0.6 * np.sin(theta_o), 0.8 * np.sin(theta_o), np.cos(theta_o)], axis=-1)
    lobe = microfacet.microfacet_brdf(i, o, alpha, lambda c: np.ones_like(c))[..., 0]
    return np.stack(
        [lobe, microfacet.smith_G1(np.cos(theta_i), alpha), microfacet.ggx_D(np.cos(theta_o), alpha),
         microfacet.half_vector_cosine(i, o)],
        axis=-1,
    )


@pytest.mark.gl
@pytest.mark.parametrize("alpha", [1e-3, 0.05, 0.4, 1.0])
def test_microfacet_glsl_equals_numpy(gl_renderer, alpha):
    ctx = gl_renderer.ctx
    builder = ShaderBuilder(include_dirs=[SHADER_DIR])
    builder.define("SIZE", f"{SIZE:.1f}")
    builder.add_source(PROBE, "probe")
    program = ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=builder.build().code)
    framebuffer = ctx.framebuffer(color_attachments=[ctx.renderbuffer((SIZE, SIZE), 4, dtype="f4")])
    try:
        gl_renderer.draw(program, framebuffer, uniforms={"alpha": alpha})
        gl = np.frombuffer(framebuffer.read(components=4, dtype="f4"), dtype=np.float32).reshape(SIZE, SIZE, 4)
    finally:
        framebuffer.color_attachments[0].release()
        framebuffer.release()
    expected = numpy_probe(alpha)
    assert np.all(np.isfinite(gl))
    error = np.abs(gl - expected) / np.maximum(np.abs(expected), 1e-3)
    assert error.max() < RELATIVE, error.reshape(-1, 4).max(axis=0)
