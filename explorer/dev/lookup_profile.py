"""
``python -m explorer.dev.lookup_profile [SIZE] [REPEATS]``: what a per-pixel table lookup costs against
Schlick's Fresnel on this GL (docs/performance.md, *Tabulated shading, re-profiled*).

Each variant is the sphere view's pixel (``shaders/views/sphere.glsl``: ``reflectance(sqrt(1 - r^2))``
inside the disc) with one way of reading a 257-entry RGB table over cos theta: the tabulated method's own
(one ``texelFetch`` of a packed interval, ``shaders/lib/bragg.glsl``'s ``packed_tabulated_rgb``), the other
exact ones (two float texels and a ``mix`` from a buffer or a 2D texture, two nearest ``texture`` reads, a
uniform block, hardware filtering of RGBA32F and of 16-bit normalised fixed point) and, for the floor, one
read (not exact).
Frames are interleaved and bounded by ``glFinish``; the minimum over the repeats is printed with the median
CPU time, as ratios to Schlick's. The minimum is the least disturbed by other processes on a shared machine.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from explorer.gpu.context import GLSL_VERSION, VERTEX_SHADER, create_context
from explorer.gpu.packed_tables import pack_table_intervals
from explorer.gpu.resources import BufferTexture, set_buffer_sampler

ENTRIES = 257

_HEAD = f"""#version {GLSL_VERSION}
uniform vec2 resolution;
uniform float F0;
out vec4 frag_colour;
"""
_MAIN = """
void main() {
    vec2 p = 2.0 * gl_FragCoord.xy / resolution - 1.0;
    float r2 = dot(p, p);
    frag_colour = r2 < 1.0 ? vec4(reflectance(sqrt(1.0 - r2)), 1.0) : vec4(0.0, 0.0, 0.0, 1.0);
}
"""
_INDEX = """int last = textureSize(table, 0).x - 1;
    float x = clamp(cos_theta, 0.0, 1.0) * float(last);
    int i = clamp(int(x), 0, max(last - 1, 0));"""
_BUFFER_INDEX = """int last = textureSize(table) - 1;
    float x = clamp(cos_theta, 0.0, 1.0) * float(last);
    int i = clamp(int(x), 0, max(last - 1, 0));"""
#: name -> (description, table texture: (dtype, filter), "block", "buffer" or "packed", the reflectance function).
VARIANTS = {
    "schlick": ("Schlick's Fresnel (the baseline)", None, """
vec3 reflectance(float c) { float m = 1.0 - c; float m2 = m * m; return vec3(F0 + (1.0 - F0) * m2 * m2 * m); }"""),
    "packed": ("one texelFetch of a packed interval, RGBA32UI buffer, 16-bit codes (the tabulated method)", "packed", """
uniform usamplerBuffer table;
vec3 reflectance(float cos_theta) {
    int intervals = textureSize(table);
    float x = clamp(cos_theta, 0.0, 1.0) * float(intervals);
    int i = min(int(x), intervals - 1);
    uvec4 texel = texelFetch(table, i);
    return uintBitsToFloat(texel.w) * mix(vec3(ivec3(texel.xyz << 16) >> 16), vec3(ivec3(texel.xyz) >> 16), x - float(i));
}"""),
    "buffer2": ("two texelFetch + mix, RGBA32F buffer texture", "buffer", f"""
uniform samplerBuffer table;
vec3 reflectance(float cos_theta) {{
    {_BUFFER_INDEX}
    return mix(texelFetch(table, i).rgb, texelFetch(table, min(i + 1, last)).rgb, x - float(i));
}}"""),
    "fetch2": ("two texelFetch + mix, RGBA32F 2D texture (the tabulated method before; a .brdf export)", ("f4", "nearest"), f"""
uniform sampler2D table;
vec3 reflectance(float cos_theta) {{
    {_INDEX}
    return mix(texelFetch(table, ivec2(i, 0), 0).rgb, texelFetch(table, ivec2(min(i + 1, last), 0), 0).rgb, x - float(i));
}}"""),
    "texture2": ("two nearest texture() + mix, RGBA32F", ("f4", "nearest"), f"""
uniform sampler2D table;
vec3 reflectance(float cos_theta) {{
    {_INDEX}
    float w = float(last + 1);
    return mix(texture(table, vec2((float(i) + 0.5) / w, 0.5)).rgb, texture(table, vec2((float(i) + 1.5) / w, 0.5)).rgb, x - float(i));
}}"""),
    "block2": ("two entries of a uniform block + mix", "block", f"""
layout(std140) uniform Table {{ vec4 entries[{ENTRIES}]; }};
vec3 reflectance(float cos_theta) {{
    int last = {ENTRIES - 1};
    float x = clamp(cos_theta, 0.0, 1.0) * float(last);
    int i = clamp(int(x), 0, last - 1);
    return mix(entries[i].rgb, entries[i + 1].rgb, x - float(i));
}}"""),
    "linear32f": ("texture() LINEAR, RGBA32F", ("f4", "linear"), """
uniform sampler2D table;
vec3 reflectance(float c) { float w = float(textureSize(table, 0).x); return texture(table, vec2((clamp(c, 0.0, 1.0) * (w - 1.0) + 0.5) / w, 0.5)).rgb; }"""),
    "linear16": ("texture() LINEAR, RGBA16 normalised (16 bits, the GPU's filter weights)", ("nu2", "linear"), """
uniform sampler2D table;
vec3 reflectance(float c) { float w = float(textureSize(table, 0).x); return texture(table, vec2((clamp(c, 0.0, 1.0) * (w - 1.0) + 0.5) / w, 0.5)).rgb; }"""),
    "buffer1": ("one texelFetch, RGBA32F buffer texture (not exact: the floor of a buffer lookup)", "buffer", f"""
uniform samplerBuffer table;
vec3 reflectance(float cos_theta) {{
    {_BUFFER_INDEX}
    return texelFetch(table, i).rgb;
}}"""),
    "nearest1": ("one nearest texture(), RGBA32F (not exact: the floor of any lookup)", ("f4", "nearest"), """
uniform sampler2D table;
vec3 reflectance(float c) { float w = float(textureSize(table, 0).x); return texture(table, vec2((clamp(c, 0.0, 1.0) * (w - 1.0) + 0.5) / w, 0.5)).rgb; }"""),
}


def lookup_table() -> np.ndarray:
    """The ``(ENTRIES, 4)`` float32 table every variant reads (random, fixed seed)."""
    return np.random.default_rng(0).random((ENTRIES, 4)).astype(np.float32)


def profile(size: int = 512, repeats: int = 61, images: dict | None = None, ctx=None) -> dict[str, dict]:
    """
    Per variant of :data:`VARIANTS`: ``min_ms``, ``cpu_ms`` (median) and their ratios to Schlick's.
    ``images``: filled with each variant's frame, ``(size, size, 3)`` rows from the bottom (tests).
    ``ctx``: the moderngl context to use (default: a new one); what is made in it is released.
    """
    import moderngl

    ctx = create_context() if ctx is None else ctx
    table = lookup_table()
    # "nu2": normalised 16-bit (GL_RGBA16). moderngl's "u2" is an integer texture, which no LINEAR filter
    # completes: it read (0, 0, 0, 1) and looked as cheap as one fetch (docs/performance.md).
    data = {"f4": table, "nu2": np.round(table * 65535).astype(np.uint16)}
    framebuffer = ctx.framebuffer(color_attachments=[ctx.renderbuffer((size, size), 4, dtype="f4")])
    block = ctx.buffer(table.tobytes())
    programs = {}
    for name, (_, texture, source) in VARIANTS.items():
        program = ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=_HEAD + source + _MAIN)
        for uniform, value in (("resolution", (float(size), float(size))), ("F0", 0.04), ("table", 0)):
            if uniform in program:
                program[uniform].value = value
        bound = None
        if texture == "block":
            program["Table"].binding = 0
        elif texture == "buffer":
            bound = BufferTexture(ctx, table.reshape(1, ENTRIES, 4))
        elif texture == "packed":
            bound = BufferTexture(ctx, pack_table_intervals(table[:, :3])[None])
        elif texture is not None:
            dtype, filtering = texture
            bound = ctx.texture((ENTRIES, 1), 4, data[dtype].tobytes(), dtype=dtype)
            bound.filter = (moderngl.LINEAR, moderngl.LINEAR) if filtering == "linear" else (moderngl.NEAREST, moderngl.NEAREST)
            bound.repeat_x = bound.repeat_y = False
        programs[name] = (program, ctx.vertex_array(program, []), bound)

    def frame(name: str) -> tuple[float, float]:
        program, vertex_array, texture = programs[name]
        if isinstance(texture, BufferTexture):
            texture.use(location=0)
            set_buffer_sampler(program, "table", 0)
        elif texture is not None:
            texture.use(location=0)
        block.bind_to_uniform_block(0)
        framebuffer.use()
        ctx.finish()
        start, cpu = time.perf_counter(), time.process_time()
        vertex_array.render(vertices=3)
        ctx.finish()
        return 1e3 * (time.perf_counter() - start), 1e3 * (time.process_time() - cpu)

    times: dict[str, list] = {name: [] for name in VARIANTS}
    for round_ in range(repeats + 2):  # two warm-up rounds
        for name in VARIANTS:
            measured = frame(name)
            if round_ >= 2:
                times[name].append(measured)
    for name in VARIANTS if images is not None else ():
        frame(name)
        images[name] = np.frombuffer(framebuffer.read(components=3, dtype="f4"), np.float32).reshape(size, size, 3)
    for program, vertex_array, texture in programs.values():
        for made in (vertex_array, program, texture):
            if made is not None:
                made.release()
    block.release()
    attachments = framebuffer.color_attachments
    framebuffer.release()
    for attachment in attachments:
        attachment.release()
    base_min = min(t[0] for t in times["schlick"])
    base_cpu = float(np.median([t[1] for t in times["schlick"]]))
    return {name: {"min_ms": min(t[0] for t in v), "cpu_ms": float(np.median([t[1] for t in v])),
                   "min_ratio": min(t[0] for t in v) / base_min,
                   "cpu_ratio": float(np.median([t[1] for t in v])) / base_cpu} for name, v in times.items()}


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    size = int(argv[0]) if argv else 512
    repeats = int(argv[1]) if len(argv) > 1 else 61
    result = profile(size, repeats)
    print(f"{size}x{size} sphere, {repeats} interleaved frames; minimum wall-clock and median CPU time, x Schlick's")
    for name, row in result.items():
        print(f"{name:<10} {row['min_ms']:7.2f} ms  x{row['min_ratio']:.2f}   CPU {row['cpu_ms']:7.2f} ms  x{row['cpu_ratio']:.2f}   {VARIANTS[name][0]}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
