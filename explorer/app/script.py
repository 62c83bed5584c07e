"""
The scripted-input robot: a session described as a list of actions, played one frame at a time through
ImGui's IO (synthesised mouse and key events, exactly what the glfw callbacks feed it), so that a slider
changes through its widget. The tests and ``bench --app`` drive the app with it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

#: Frames an action waits for its item to appear before it is logged as missing and skipped.
MISSING_ITEM_FRAMES = 60


@dataclass
class ScriptState:
    """A scripted session: actions, the mouse they drive, and the frames they are in."""

    actions: list
    index: int = 0
    frame_in_action: int = 0
    mark: str | None = None
    mouse: tuple[float, float] = (-1.0, -1.0)
    waited: int = 0
    log: list = field(default_factory=list)


class ScriptRobot:
    """
    Plays a :class:`ScriptState` on an app (its ``state``, and ``idle()``: nothing left to draw).

    Actions (dicts): ``{"wait": N}`` frames; ``{"wait_complete": true}`` until the active view is fully
    refined; ``{"wait_for": NAME}`` until a panel's report ``state.NAME`` is a dict not ``running`` (the
    Design window's worker); ``{"wait_accuracy": true}`` until the accuracy badge shows the current values; ``{"wait_converged": true}``
    until the env mode holds its target samples per pixel;
    ``{"drag": LABEL, "from": F0, "to": F1, "frames": N}`` press at fraction F0 of the item's
    width, move to F1 over N frames, release (sliders are labelled ``param:NAME``); with ``"hold": M,
    "hold_until_draft": VIEW`` it holds still at F1 for up to M frames until VIEW shows a draft table; ``{"click": LABEL}``
    (``preset_combo``, ``preset:NAME``, ``mode:lit``, ``param:method`` then ``method:N``, ``menu_file`` then
    ``menu_open``, ``menu_help`` then ``menu_about``, the Materials list's ``material:I``,
    ``material:I:visible``, ``material:I:solo``, ``material:I:close``, ...); ``{"set": {NAME: VALUE}}`` (bench only: no
    UI); ``{"mark": TEXT}`` tags the following frames; ``{"screenshot": PATH}`` the active view (waits
    until complete; in ``env``, until a whole sample); ``{"window_screenshot": PATH}`` the whole window;
    ``{"type": LABEL, "text": TEXT}`` clicks a text field (one that selects all on focus), types TEXT and
    presses Enter (the Inverse window's ``inverse:R_1``, ``inverse:sigma_typed_1``); ``{"file_path": PATH}`` types PATH into the Files tab's path field; ``{"view_size": N}`` picks the
    sphere's resolution (the combo's values); ``{"key": "F12"}`` presses and releases a key (ImGui's
    name), then waits for a screenshot it asked for; ``{"focus": TITLE}`` brings a docked window to the
    front; ``{"write": PATH, "text": TEXT}`` writes a file (a user's editor between two reloads);
    ``{"wheel": LABEL, "y": Y}`` turns the mouse wheel Y notches over an item (scrolls its window: an item below
    the window's edge comes into view); ``{"dialog": [PATH, ...]}`` answers the next File > Open... (:mod:`explorer.app.dialogs`);
    ``{"save_slice": PATH}`` saves the Slice window's linear image once complete; ``{"quit": true}``.
    """

    def __init__(self, actions: list):
        self.script = ScriptState(list(actions))

    @property
    def mark(self) -> str | None:
        return self.script.mark

    @property
    def log(self) -> list:
        return self.script.log

    def step(self, app, io) -> None:
        """Feed one frame of the script to ImGui's IO."""
        script, state = self.script, app.state
        if script.index >= len(script.actions):
            state.quit = True
            return
        action = script.actions[script.index]
        step = script.frame_in_action
        script.frame_in_action += 1
        kind = next((k for k in ACTIONS if k in action), None)
        if kind is None:
            script.log.append(f"unknown action {action!r}")
            done = True
        else:
            done = bool(ACTIONS[kind](self, app, io, action, step))
        if done:
            script.index += 1
            script.frame_in_action = 0

    # -- pointer actions ----------------------------------------------------------------------------

    @staticmethod
    def _target_point(state, label: str, fraction: float = 0.5) -> tuple[float, float] | None:
        state.script_target = label
        rect = state.rects.get(label)
        if rect is None or label in state.hidden:
            return None
        x0, y0, x1, y1 = rect
        return x0 + fraction * (x1 - x0), 0.5 * (y0 + y1)

    def _mouse(self, io, point) -> None:
        self.script.mouse = point
        io.add_mouse_pos_event(float(point[0]), float(point[1]))

    def _missing(self, kind: str, label: str) -> bool:
        """The item is not drawn (yet): retry from the action's first frame; True when it is given up."""
        script = self.script
        script.frame_in_action = 0
        script.waited += 1
        if script.waited > MISSING_ITEM_FRAMES:
            script.log.append(f"{kind}: no item {label!r}")
            script.waited = 0
            return True
        return False

    def _drag(self, app, io, action: dict, step: int) -> bool:
        state = app.state
        frames = int(action.get("frames", 10))
        f0, f1 = float(action.get("from", 0.5)), float(action.get("to", 0.5))
        held = step - frames - 2  # frames held still at F1 before the release
        until = action.get("hold_until_draft")  # a view shown from a draft table ends the hold (a loaded machine's
        # worker thread may need longer than the drag itself)
        if held >= 0 and until is not None and held < int(action.get("hold", 0)) and until not in app.scheduler.drafts:
            return False
        if step == 0:
            point = self._target_point(state, action["drag"], f0)
            if point is None:
                return self._missing("drag", action["drag"])
            self._mouse(io, point)
        elif step == 1:
            io.add_mouse_button_event(0, True)
        elif step <= frames + 1:
            t = (step - 1) / frames
            point = self._target_point(state, action["drag"], f0 + t * (f1 - f0))
            if point is not None:
                self._mouse(io, point)
        else:
            io.add_mouse_button_event(0, False)
            self.script.log.append(f"dragged {action['drag']}")
            return True
        return False

    def _click(self, state, io, action: dict, step: int) -> bool:
        if step == 0:
            point = self._target_point(state, action["click"])
            if point is None:
                return self._missing("click", action["click"])
            self.script.waited = 0
            self._mouse(io, point)
        elif step == 1:
            io.add_mouse_button_event(0, True)
        elif step == 2:
            io.add_mouse_button_event(0, False)
        else:
            self.script.log.append(f"clicked {action['click']}")
            return True
        return False

    def _type(self, state, io, action: dict, step: int) -> bool:
        """Click the field (it selects its text), type the characters, press Enter."""
        from imgui_bundle import imgui

        if step <= 2:  # press and release on the field; at step 0 True only when it never appeared
            return self._click(state, io, {"click": action["type"]}, step)
        if step == 3:
            pass  # a frame for the field to take focus and select its text
        elif step == 4:
            io.add_input_characters_utf8(str(action["text"]))
        elif step == 5:
            io.add_key_event(imgui.Key.enter, True)
        elif step == 6:
            io.add_key_event(imgui.Key.enter, False)
        else:
            self.script.log.append(f"typed {action['type']}")
            return True
        return False


# -- the actions: {"KIND": ...} -> handler(robot, app, io, action, step) -> done ----------------------


def _timed_out(robot, action, step: int, what: str, default: int) -> bool:
    if step > int(action.get("timeout", default)):
        robot.script.log.append(f"{what}: timed out")
        return True
    return False


def _wait(robot, app, io, action, step):
    return step >= int(action["wait"])


def _wait_for(robot, app, io, action, step):  # until a panel's report (state.NAME) says it is no longer running
    report = getattr(app.state, str(action["wait_for"]), None)
    done = step > 1 and isinstance(report, dict) and not report.get("running", False)
    return done or _timed_out(robot, action, step, f"wait_for {action['wait_for']}", 3000)


def _wait_complete(robot, app, io, action, step):
    return (step > 1 and app.idle()) or _timed_out(robot, action, step, "wait_complete", 2000)


def _wait_accuracy(robot, app, io, action, step):  # the Parameters window's badge shows the current values
    state = app.state
    done = step > 1 and bool(state.accuracy) and not state.accuracy.endswith("(updating)")
    if done:
        robot.script.log.append(f"accuracy: {state.accuracy}")
    return done or _timed_out(robot, action, step, "wait_accuracy", 2000)


def _wait_converged(robot, app, io, action, step):  # the env mode holds its target samples per pixel
    done = step > 1 and bool(app.state.env_progress.get("converged"))
    if done:
        robot.script.log.append(f"converged at {app.state.env_progress.get('samples')} samples per pixel")
    return done or _timed_out(robot, action, step, "wait_converged", 3000)


def _mark(robot, app, io, action, step):
    robot.script.mark = action["mark"]
    return True


def _set(robot, app, io, action, step):
    state = app.state
    state.values = state.material.resolve({**state.values, **action["set"]})
    return True


def _screenshot(robot, app, io, action, step):
    state = app.state
    if step == 0:
        state.pending_screenshot = str(action["screenshot"])
    return state.pending_screenshot is None or _timed_out(robot, action, step, "screenshot", 3000)


def _key(robot, app, io, action, step):
    from imgui_bundle import imgui

    state = app.state
    if step <= 1:
        io.add_key_event(getattr(imgui.Key, str(action["key"]).lower()), step == 0)
        return False
    done = state.pending_screenshot is None or _timed_out(robot, action, step, f"key {action['key']}", 3000)
    if done:
        robot.script.log.append(f"pressed {action['key']}")
    return done


def _window_screenshot(robot, app, io, action, step):
    state = app.state
    if step == 0:
        state.pending_window_shot = str(action["window_screenshot"])
    return step > 0 and state.pending_window_shot is None


def _assign(name: str, convert):
    def handler(robot, app, io, action, step):
        setattr(app.state, name, convert(action[ACTION_OF_FIELD[name]]))
        return True
    return handler


ACTION_OF_FIELD = {"file_path": "file_path", "focus_request": "focus"}


def _view_size(robot, app, io, action, step):  # a fixed resolution (the combo's values), no longer fitting the window
    app.state.view_size, app.state.view_size_auto = int(action["view_size"]), False
    return True


def _dialog(robot, app, io, action, step):  # the answer the next File > Open... gets, instead of a person's
    app.state.dialog_answers.append([str(path) for path in action["dialog"]])
    robot.script.log.append(f"queued dialog answer ({len(action['dialog'])} paths)")
    return True


def _save_slice(robot, app, io, action, step):  # the Slice window's linear image (.npy), once it is complete
    state = app.state
    if step == 0:
        state.pending_slice_save = str(action["save_slice"])
    return state.pending_slice_save is None or _timed_out(robot, action, step, "save_slice", 2000)


def _write(robot, app, io, action, step):  # what a user's editor does to the material file between two reloads
    Path(action["write"]).write_text(str(action["text"]))
    robot.script.log.append(f"wrote {action['write']}")
    return True


def _wheel(robot, app, io, action, step):  # the mouse over an item, its wheel turned: scrolls the window under it
    if step == 0:
        point = robot._target_point(app.state, action["wheel"])
        if point is None:
            return robot._missing("wheel", action["wheel"])
        robot._mouse(io, point)
    elif step == 1:
        io.add_mouse_wheel_event(0.0, float(action.get("y", -10)))
    elif step >= 3:
        robot.script.log.append(f"wheel over {action['wheel']}")
        return True
    return False


def _quit(robot, app, io, action, step):
    app.state.quit = True
    return True


#: Each action kind, in the order a script's dict is matched (the first key found decides).
ACTIONS = {
    "wait": _wait,
    "wait_for": _wait_for,
    "wait_complete": _wait_complete,
    "wait_accuracy": _wait_accuracy,
    "wait_converged": _wait_converged,
    "mark": _mark,
    "set": _set,
    "drag": lambda robot, app, io, action, step: robot._drag(app, io, action, step),
    "click": lambda robot, app, io, action, step: robot._click(app.state, io, action, step),
    "type": lambda robot, app, io, action, step: robot._type(app.state, io, action, step),
    "screenshot": _screenshot,
    "key": _key,
    "window_screenshot": _window_screenshot,
    "file_path": _assign("file_path", str),
    "view_size": _view_size,
    "dialog": _dialog,
    "save_slice": _save_slice,
    "focus": _assign("focus_request", str),  # bring a docked window's tab to the front, as a click on it does
    "write": _write,
    "wheel": _wheel,
    "quit": _quit,
}
