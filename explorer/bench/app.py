"""
``bench --app``: the explorer's frame times while a slider is dragged (sphere, lit, env, views, meshes).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from explorer.bench.common import _progress
from explorer.materials.methods import BraggMethod
from explorer.resources import SHADER_DIR
from explorer.materials.models import BraggStackModel

# --------------------------------------------------------------------------------------------------
# bench --app: the explorer's frame times while a slider is dragged


#: The methods of bragg_mirror.brd timed by ``bench --app``, fastest first.
APP_METHODS = tuple((int(m), name) for m, name in (
    (BraggMethod.TABULATED, "tabulated"), (BraggMethod.BASIC, "basic"), (BraggMethod.SUBDIVIDED, "subdivided s = 3"),
    (BraggMethod.IMPROVED, "improved s = 3"), (BraggMethod.REFERENCE, "reference")))
#: The sphere's modes timed per method (the env mode is timed on the stack: :data:`APP_ENV_VALUES`).
APP_MODES = ("sphere", "lit")
#: The env mode's material (``shaders/bragg_stack.brd``) and values: the two-layer stack, Lambda_1 dragged.
APP_ENV_MATERIAL = f"{BraggStackModel.name}.brd"
APP_ENV_VALUES = {"layers": 2}
APP_ENV_SLIDER = "param:Lambda_1"
#: Frames per drag (``bench --app --frames``): about 2 px a frame (see :func:`_drag`).
APP_FRAMES = 60
#: The goals: frames while a slider moves, and the env view's first pass.
APP_GOAL_FPS = 30.0
APP_GOAL_FIRST_PASS_MS = 33.0


def _drag(mark: str, slider: str, frames: int, **hold) -> list:
    # About 2 px a frame at 60 frames (more with fewer): an integer slider (1 nm steps, ~8 nm a pixel) changes on every frame.
    return [{"mark": mark}, {"drag": slider, "from": 0.15, "to": 0.85, "frames": frames, **hold}, {"mark": None}, {"wait": 3}]


def app_bench_script(frames: int = APP_FRAMES) -> list:
    """The scripted session of ``bench --app``: per mode of :data:`APP_MODES` and method, drag Lambda through the UI for ``frames`` frames."""
    script: list = [{"wait": 3}, {"wait_complete": True, "timeout": 600}]
    for mode in APP_MODES:
        script += [{"click": f"mode:{mode}"}, {"wait": 3}]
        for method, _name in APP_METHODS:
            script += [{"set": {"method": method}}, {"wait": 8}] + _drag(f"{mode} {method}", "param:Lambda", frames)
    return script + app_view_steps(frames) + app_mesh_steps(frames) + [{"quit": True}]


def app_env_script(frames: int = APP_FRAMES) -> list:
    """The env session of ``bench --app`` (on :data:`APP_ENV_MATERIAL`): the mode's first frames, then a drag of :data:`APP_ENV_SLIDER`."""
    return ([{"wait": 3}, {"set": dict(APP_ENV_VALUES)}, {"wait": 3}, {"mark": "env open"}, {"click": "mode:env"}, {"wait": 10},
             {"mark": None}] + _drag("env", APP_ENV_SLIDER, frames) + [{"quit": True}])


def _frame_row(chosen: list[dict], drag: list[dict], env: bool = False) -> dict:
    """Frame times (ms) of the frames ``chosen`` (a drag's, where the values changed) and how often the sphere changed."""
    ms = np.array([f["ms"] for f in chosen[2:] or chosen])
    # How often the sphere shows new values: its tables may be one frame late (built on a worker thread).
    if env:  # the env render restarts on new values
        updates = sum(1 for f in drag[1:] if f["env"]["first_pass"])
    else:
        generations = [f["main"].get("generation", 0) for f in drag]
        updates = sum(1 for a, b in zip(generations, generations[1:]) if b != a)
    seconds = 1e-3 * sum(f["ms"] for f in drag[1:])
    return {
        "frames": int(ms.size), "median_ms": float(np.median(ms)), "p90_ms": float(np.percentile(ms, 90)),
        "max_ms": float(ms.max()), "fps": float(1e3 / np.median(ms)),
        "sphere_updates_per_s": updates / seconds if seconds > 0 else 0.0,
        "gl_ms": float(np.median([f["gl_ms"] for f in chosen])), "ui_ms": float(np.median([f["ui_ms"] for f in chosen])),
    }


def summarise_app_frames(frames: list[dict]) -> list[dict]:
    """Per mode and method: frame times (ms) of the frames spent dragging, and the resolution shown meanwhile."""
    rows = []
    for mode in APP_MODES:
        for method, name in APP_METHODS:
            mark = f"{mode} {method}"
            # Only frames where the parameter changed: a frame that redraws nothing new is not a drag frame.
            drag = [f for f in frames if f.get("mark") == mark and f.get("dragging")]
            chosen = [f for f in drag if f.get("changed")]
            if not chosen:
                continue
            # What most of those frames showed (a draw slowed by other processes may make one a preview).
            previews = [tuple(f["main"]["preview"]) for f in chosen if f["main"]["has_preview"] and not f["main"]["complete"]]
            shown = (f"{previews[-1][0]}x{previews[-1][1]} preview" if 2 * len(previews) > len(chosen)
                     else f"{chosen[-1]['main']['size'][0]}x{chosen[-1]['main']['size'][1]} full")
            rows.append({"mode": mode, "method": method, "name": name, **_frame_row(chosen, drag), "while_dragging": shown})
    return rows


def summarise_env_frames(frames: list[dict]) -> dict | None:
    """The env session: its first pass on opening (ms), the first passes while the slider moves, and the frame times."""
    opening = [f["env"]["ms"] for f in frames if f.get("mark") == "env open" and f.get("env", {}).get("first_pass")]
    drag = [f for f in frames if f.get("mark") == "env" and f.get("dragging")]
    chosen = [f for f in drag if f.get("changed")]
    if not opening or not chosen:
        return None
    first_passes = [f["env"]["ms"] for f in drag if f["env"]["first_pass"]]
    return {"mode": "env", "material": APP_ENV_MATERIAL, "values": dict(APP_ENV_VALUES), **_frame_row(chosen, drag, env=True),
            "first_pass_ms": float(opening[0]), "drag_first_pass_median_ms": float(np.median(first_passes or [np.nan])),
            "drag_first_pass_max_ms": float(np.max(first_passes or [np.nan])),
            "samples_after_drag": int(drag[-1]["env"]["samples"])}


def _app_session(material, script: list, size: int) -> dict:
    """One scripted session of the explorer on ``material``; its report."""
    import tempfile

    from explorer.app import App

    with tempfile.TemporaryDirectory() as directory:
        report = Path(directory) / "report.json"
        App(material, script=script, report=report, view_size=size, is_default=True).run()
        return json.loads(report.read_text())


def run_app_bench(as_json: bool = False, size: int = 512, frames: int = APP_FRAMES) -> list[dict]:
    """
    Open the explorer (on a virtual display when there is none) on the default mirror with a ``size``²
    sphere, drag the Lambda slider through the UI for ``frames`` frames per mode (:data:`APP_MODES`) and
    method, with each new view (:func:`app_view_cases`: the Plots window's plots, the Texture window's textured
    mirror) beside the sphere, then on the two-layer stack in the env mode (its first pass on opening, then a
    drag of Lambda_1), and print the frame times (wall clock between frames: UI, drawing, table rebuilds and all).
    """
    from explorer.app.xvfb import display_environment
    from explorer.resources import DEFAULT_MATERIAL

    with display_environment() as display:
        _progress(f"bench --app: scripted session on DISPLAY={display}, {size}x{size} sphere, {frames} frames of drag per mode and method")
        document = _app_session(DEFAULT_MATERIAL, app_bench_script(frames), size)
        _progress(f"bench --app: the env mode on {APP_ENV_MATERIAL} ({APP_ENV_VALUES})")
        env_document = _app_session(SHADER_DIR / APP_ENV_MATERIAL, app_env_script(frames), size)
    rows = summarise_app_frames(document["frames"])
    env = summarise_env_frames(env_document["frames"])
    mesh_rows = summarise_mesh_frames(document["frames"])
    views = summarise_view_frames(document["frames"])
    if as_json:
        print(json.dumps({"size": size, "frames": frames, "window": list(document.get("window", [])), "rows": rows, "env": env,
                          "mesh_rows": mesh_rows, "views": views}, indent=2))
        return rows + ([env] if env else [])
    print(f"Explorer frame times while dragging Lambda ({size}x{size} sphere, 1280x800 window, {os.cpu_count()} CPUs; goal >= {APP_GOAL_FPS:g} fps):")
    print(f"{'mode':<7}{'method':<22} {'median':>8} {'p90':>8} {'max':>8} {'fps':>6} {'sphere/s':>9}  {'GL work':>8} {'UI':>6}  shown while dragging")
    for row in rows + mesh_rows:
        print(f"{row['mode']:<7}{row['method']} {row['name']:<20} {row['median_ms']:7.1f}ms {row['p90_ms']:7.1f}ms {row['max_ms']:7.1f}ms "
              f"{row['fps']:6.1f} {row['sphere_updates_per_s']:9.1f}  {row['gl_ms']:7.1f}ms {row['ui_ms']:5.1f}ms  {row['while_dragging']}")
    if env:
        print(f"{'env':<7}{APP_ENV_MATERIAL + ' layers = 2':<22} {env['median_ms']:7.1f}ms {env['p90_ms']:7.1f}ms {env['max_ms']:7.1f}ms "
              f"{env['fps']:6.1f} {env['sphere_updates_per_s']:9.1f}  {env['gl_ms']:7.1f}ms {env['ui_ms']:5.1f}ms")
        print(f"env first pass: {env['first_pass_ms']:.1f} ms on opening; while dragging median {env['drag_first_pass_median_ms']:.1f} ms, "
              f"max {env['drag_first_pass_max_ms']:.1f} ms (goal <= {APP_GOAL_FIRST_PASS_MS:g} ms)")
    print("fps: frames while the slider moves; sphere/s: frames that show new parameter values on the sphere")
    print_view_frames(views, size)
    return rows + ([env] if env else [])


def print_view_frames(views: list[dict], size: int) -> None:
    """The table of :func:`summarise_view_frames`."""
    print(f"New views (Plots, Texture) in their windows beside the {size}x{size} sphere, tabulated method, Lambda dragged "
          f"(goal >= {APP_GOAL_FPS:g} fps; the textured view shows draft tables while dragging):")
    print(f"{'view':<10} {'shown':>9} {'median':>8} {'p90':>8} {'max':>8} {'fps':>6} {'sphere/s':>9} {'view/s':>7} {'draft':>6}")
    for row in views:
        print(f"{row['view']:<10} {row['size'][0]:>4}x{row['size'][1]:<4} {row['median_ms']:7.1f}ms {row['p90_ms']:7.1f}ms "
              f"{row['max_ms']:7.1f}ms {row['fps']:6.1f} {row['sphere_updates_per_s']:9.1f} {row['view_updates_per_s']:7.1f} "
              f"{100 * row['draft_fraction']:5.0f}%")
    print("view/s: frames that show new parameter values in the view's window; draft: drag frames showing a draft table")


#: ``bench --app``'s views: the Plots window's plots (:data:`explorer.views.geometry.PLOT_VIEWS`),
#: then the Texture window's textured mirror, as (mark, window, the scheduler's job, plot to choose or None).
def app_view_cases() -> tuple[tuple[str, str, str, str | None], ...]:
    from explorer.views.geometry import PLOT_VIEWS

    return tuple((view, "Plots", "plot", view) for view in PLOT_VIEWS) + (("textured", "Texture", "textured", None),)


def app_view_steps(frames: int) -> list:
    """Drag Lambda (tabulated method, sphere mode) with each plot shown in the Plots window, then the Texture window."""
    steps: list = [{"click": "mode:sphere"}, {"set": {"method": int(BraggMethod.TABULATED)}}, {"wait": 3}]
    for mark, window, job, plot in app_view_cases():
        steps += [{"focus": window}, {"wait": 3}]
        if plot is not None:
            steps += [{"click": "plot_combo"}, {"wait": 2}, {"click": f"plot:{plot}"}, {"wait": 3}]
        report = "plots" if window == "Plots" else "texture_view"
        # The textured view's drafts come from a worker thread: on a loaded machine the press is held still
        # until one is shown, so the row measures drafts rather than the machine's load.
        hold = {"hold": 600, "hold_until_draft": job} if job == "textured" else {}
        steps += [{"wait_for": report}] + _drag(f"view {mark}", "param:Lambda", frames, **hold) + [{"wait_for": report}]
    return steps


def summarise_view_frames(frames: list[dict]) -> list[dict]:
    """Per case of :func:`app_view_cases`: the frame times while dragging, how often the view followed, and its drafts."""
    rows = []
    for mark, _window, job, _plot in app_view_cases():
        drag = [f for f in frames if f.get("mark") == f"view {mark}" and f.get("dragging")]
        chosen = [f for f in drag if f.get("changed")]
        if not chosen:
            continue
        views = [f["main"].get("views", {}).get(job, {}) for f in drag]
        generations = [v.get("generation", 0) for v in views]
        seconds = 1e-3 * sum(f["ms"] for f in drag[1:])
        updates = sum(1 for a, b in zip(generations, generations[1:]) if b != a)
        rows.append({"view": mark, "job": job, "size": views[-1].get("size", [0, 0]), **_frame_row(chosen, drag),
                     "view_updates_per_s": updates / seconds if seconds > 0 else 0.0,
                     "draft_fraction": float(np.mean([bool(v.get("draft")) for v in views]))})
    return rows


#: ``bench --app``'s mesh cases: the Sphere window's teapot, lit and under the environment (tabulated method).
APP_MESH_CASES = (("teapot lit", "mode:lit"), ("teapot env", "mode:env"))


def app_mesh_steps(frames: int) -> list:
    """Drag Lambda with the teapot shown (Switch model), lit and in the env mode (its progressive first passes)."""
    steps: list = [{"set": {"method": int(BraggMethod.TABULATED)}}, {"click": "model_combo"}, {"click": "model:teapot"}]
    for mark, mode in APP_MESH_CASES:
        steps += [{"click": mode}, {"wait": 8}] + _drag(mark, "param:Lambda", frames)
    return steps


def summarise_mesh_frames(frames: list[dict]) -> list[dict]:
    """The mesh cases' frame times while dragging (:data:`APP_MESH_CASES`)."""
    rows = []
    for mark, mode in APP_MESH_CASES:
        drag = [f for f in frames if f.get("mark") == mark and f.get("dragging")]
        chosen = [f for f in drag if f.get("changed")]
        if chosen:
            rows.append({"mode": mode.split(":")[1], "method": int(BraggMethod.TABULATED), "name": mark,
                         **_frame_row(chosen, drag, env=mode == "mode:env"), "while_dragging": mark})
    return rows
