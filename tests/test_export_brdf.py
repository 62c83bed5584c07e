"""
``export --to brdf``: one self-contained file for Disney BRDF Explorer. Each export is checked as BRDF
Explorer would load it: no line starting with '#', only float / bool / color parameters, compiled in a
``#version 410`` core context behind the template interface (``uniform float NAME;``, ``vec3`` for
colours, then the shader section verbatim), and its image slice compared with ``render --view slice`` of
the original material (its numpy twin, which the GL view equals): within 1e-3 of the slice's peak for every
method, except the thin film's methods 1-3, whose inlined 4096 x 2 table Mesa's compiler takes many minutes
over (not checked here).
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import run_cli, running_in_ci
from explorer.materials.brd import load_material
from explorer.resources import material_path

#: BRDF Explorer's image-slice template (src/shaderTemplates/brdftemplateImageSlice.frag), its geometry
#: as is, writing the BRDF unclamped to a float target; texCoord from the pixel as our slice view's.
TEMPLATE = """#version 410
uniform vec2 resolution;
out vec4 fragColor;
::INSERT_UNIFORMS_HERE::
::INSERT_BRDF_FUNCTION_HERE::
vec3 rotate_vector(vec3 v, vec3 axis, float angle) {
    vec3 n;
    axis = normalize(axis);
    n = axis * dot(axis, v);
    return n + cos(angle) * (v - n) + sin(angle) * cross(axis, v);
}
void main() {
    vec3 normal = vec3(0, 0, 1), tangent = vec3(1, 0, 0), bitangent = vec3(0, 1, 0);
    const float M_PI = 3.1415926535897932384626433832795;
    vec2 texCoord = 0.5 * M_PI * vec2(gl_FragCoord.x / resolution.x, (resolution.y - gl_FragCoord.y) / resolution.y);
    float thetaH = texCoord.r, thetaD = texCoord.g, phiH = 0.0, phiD = 0.5 * M_PI;
    vec3 H = vec3(sin(thetaH) * cos(phiH), sin(thetaH) * sin(phiH), cos(thetaH));
    vec3 D = vec3(sin(thetaD) * cos(phiD), sin(thetaD) * sin(phiD), cos(thetaD));
    vec3 L = rotate_vector(rotate_vector(D, bitangent, thetaH), normal, phiH);
    vec3 V = 2 * dot(H, L) * H - L;
    fragColor = vec4(BRDF(L, V, normal, tangent, bitangent), 1.0);
}
"""
VERTEX = """#version 410
in vec2 position;
void main() { gl_Position = vec4(position, 0.0, 1.0); }
"""
SIZE = (48, 32)


def parse_brdf(text):
    """(parameters, shader) of a .brdf as BRDF Explorer reads it: '#' lines dropped everywhere."""
    lines = [line for line in text.splitlines() if not line.startswith("#")]
    start, end = lines.index("::begin parameters"), lines.index("::end parameters")
    parameters = [line.split() for line in lines[start + 1:end] if line.strip()]
    s, e = lines.index("::begin shader"), lines.index("::end shader")
    return parameters, "\n".join(lines[s + 1:e])


@pytest.fixture(scope="module")
def core410(gl_renderer):
    """The session's GL context (a core profile): a #version 410 shader compiles in it where it is 4.1 or later.
    A second standalone context would become current and take the session's renderer off its own."""
    ctx = gl_renderer.ctx
    if ctx.version_code < 410:
        message = f"the OpenGL context is {ctx.version_code}, not 4.1 core or later"
        if running_in_ci():
            pytest.fail(message, pytrace=False)
        pytest.skip(message)
    return ctx


def slice_of_export(ctx, text):
    parameters, shader = parse_brdf(text)
    uniforms, values = [], {}
    for kind, name, *rest in parameters:
        assert kind in ("float", "bool", "color"), kind
        if kind == "color":
            uniforms.append(f"uniform vec3 {name};")
            values[name] = tuple(float(v) for v in rest)
        elif kind == "bool":
            uniforms.append(f"uniform bool {name};")
            values[name] = bool(int(rest[0]))
        else:
            uniforms.append(f"uniform float {name};")
            values[name] = float(rest[2])
    source = TEMPLATE.replace("::INSERT_UNIFORMS_HERE::", "\n".join(uniforms)).replace("::INSERT_BRDF_FUNCTION_HERE::", shader)
    program = ctx.program(vertex_shader=VERTEX, fragment_shader=source)
    for name, value in values.items():
        if name in program:
            program[name].value = value
    program["resolution"].value = tuple(float(s) for s in SIZE)
    quad = ctx.buffer(np.array([-1, -1, 1, -1, -1, 1, 1, 1], "f4").tobytes())
    vao = ctx.vertex_array(program, [(quad, "2f", "position")])
    target = ctx.renderbuffer(SIZE, 4, dtype="f4")
    fbo = ctx.framebuffer(color_attachments=[target])
    fbo.use()
    vao.render(mode=ctx.TRIANGLE_STRIP)
    image = np.frombuffer(fbo.read(components=4, dtype="f4"), np.float32).reshape(SIZE[1], SIZE[0], 4)[::-1, :, :3]
    for thing in (fbo, target, vao, quad, program):
        thing.release()
    return image.astype(np.float64)


CASES = [("bragg_mirror", {"method": m}) for m in range(5)] + [
    ("thin_film", {"method": m, "alpha": 0.3}) for m in (0, 4, 5)] + [
    ("bragg_layer", {"method": m, "rho_d": (0.3, 0.2, 0.1), "alpha": 0.25}) for m in (0, 1, 2, 3, 4)]


@pytest.mark.gl
@pytest.mark.parametrize("name, overrides", CASES, ids=[f"{n}-method{o['method']}" for n, o in CASES])
def test_exported_slice_equals_the_original(core410, name, overrides):
    from explorer.materials.export_brdf import brdf_text
    from explorer.views.geometry import above_surface, brdf_view_geometry

    material = load_material(material_path(name))
    values = material.resolve(overrides)
    text = brdf_text(material, values)
    assert not any(line.lstrip().startswith("#") for line in text.splitlines())
    exported = slice_of_export(core410, text)
    # render --view slice --engine numpy (the GL view's twin; this test holds its own 4.1 core context)
    from explorer.materials.models import model_for
    from explorer.views.render import render_numpy

    original = render_numpy(model_for(material, material.physical_values(values)), "slice", *SIZE).astype(np.float64)
    L, V, N, *_ = brdf_view_geometry("slice", *SIZE)
    shown = above_surface(L, V, N)[..., None] & np.isfinite(exported)
    exported = np.where(shown, exported, 0.0)
    peak = np.abs(original).max()
    assert peak > 1e-3
    np.testing.assert_allclose(exported, original, rtol=0, atol=1e-3 * peak)


def test_cli_writes_the_file_and_refuses_others(tmp_path):
    out = tmp_path / "film.brdf"
    run = run_cli("export", "thin_film", "--set", "method=4", "--to", "brdf", out)
    assert run.returncode == 0, run.stderr
    parameters, shader = parse_brdf(out.read_text())
    assert {p[1] for p in parameters} == {p.name for p in load_material(material_path("thin_film")).parameters}
    assert "vec3 BRDF(" in shader and "sampler2D" not in shader
    for args, hint in ((["export", "ggx_schlick", "--to", "brdf", tmp_path / "x.brdf"], "no self-contained"),
                       (["export", "thin_film", "--to", "brdf", tmp_path / "x.txt"], ".brdf")):
        run = run_cli(*args)
        assert run.returncode != 0 and len(run.stderr.strip().splitlines()) == 1 and hint in run.stderr, run.stderr
