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
    Design window's worker); ``{"wait_accuracy": true}`` until the accuracy badge shows the current values;
    ``{"drag": LABEL, "from": F0, "to": F1, "frames": N}`` press at fraction F0 of the item's
    width, move to F1 over N frames, release (sliders are labelled ``param:NAME``); ``{"click": LABEL}``
    (``preset_combo``, ``preset:NAME``, ``mode:lit``, ...); ``{"set": {NAME: VALUE}}`` (bench only: no
    UI); ``{"mark": TEXT}`` tags the following frames; ``{"screenshot": PATH}`` the active view (waits
    until complete; in ``env``, until a whole sample); ``{"window_screenshot": PATH}`` the whole window;
    ``{"type": LABEL, "text": TEXT}`` clicks a text field (one that selects all on focus), types TEXT and
    presses Enter (the Inverse window's ``inverse:R_1``, ``inverse:sigma_typed_1``); ``{"file_path": PATH}`` types PATH into the Files tab's path field; ``{"view_size": N}`` picks the
    sphere's resolution (the combo's values); ``{"key": "F12"}`` presses and releases a key (ImGui's
    name), then waits for a screenshot it asked for; ``{"focus": TITLE}`` brings a docked window to the
    front; ``{"write": PATH, "text": TEXT}`` writes a file (a user's editor between two reloads);
    ``{"quit": true}``.
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
        done = False
        if "wait" in action:
            done = step >= int(action["wait"])
        elif "wait_for" in action:  # until a panel's report (state.NAME) says it is no longer running
            report = getattr(state, str(action["wait_for"]), None)
            done = step > 1 and isinstance(report, dict) and not report.get("running", False)
            if step > int(action.get("timeout", 3000)):
                script.log.append(f"wait_for {action['wait_for']}: timed out")
                done = True
        elif "wait_complete" in action:
            done = step > 1 and app.idle()
            if step > int(action.get("timeout", 2000)):
                script.log.append("wait_complete: timed out")
                done = True
        elif "wait_accuracy" in action:  # the Parameters window's accuracy badge shows the current values
            done = step > 1 and bool(state.accuracy) and not state.accuracy.endswith("(updating)")
            if done:
                script.log.append(f"accuracy: {state.accuracy}")
            if step > int(action.get("timeout", 2000)):
                script.log.append("wait_accuracy: timed out")
                done = True
        elif "mark" in action:
            script.mark = action["mark"]
            done = True
        elif "set" in action:
            state.values = state.material.resolve({**state.values, **action["set"]})
            done = True
        elif "drag" in action:
            done = self._drag(state, io, action, step)
        elif "click" in action:
            done = self._click(state, io, action, step)
        elif "type" in action:
            done = self._type(state, io, action, step)
        elif "screenshot" in action:
            if step == 0:
                state.pending_screenshot = str(action["screenshot"])
            done = state.pending_screenshot is None
            if step > int(action.get("timeout", 3000)):
                script.log.append("screenshot: timed out")
                done = True
        elif "key" in action:
            from imgui_bundle import imgui

            if step <= 1:
                io.add_key_event(getattr(imgui.Key, str(action["key"]).lower()), step == 0)
            else:
                done = state.pending_screenshot is None
                if step > int(action.get("timeout", 3000)):
                    script.log.append(f"key {action['key']}: timed out")
                    done = True
                if done:
                    script.log.append(f"pressed {action['key']}")
        elif "window_screenshot" in action:
            if step == 0:
                state.pending_window_shot = str(action["window_screenshot"])
            done = step > 0 and state.pending_window_shot is None
        elif "file_path" in action:
            state.file_path = str(action["file_path"])
            done = True
        elif "view_size" in action:
            state.view_size = int(action["view_size"])
            done = True
        elif "focus" in action:  # bring a docked window's tab to the front, as a click on its tab does
            state.focus_request = str(action["focus"])
            done = True
        elif "write" in action:  # what a user's editor does to the material file between two reloads
            Path(action["write"]).write_text(str(action["text"]))
            script.log.append(f"wrote {action['write']}")
            done = True
        elif "quit" in action:
            state.quit = True
            done = True
        else:
            script.log.append(f"unknown action {action!r}")
            done = True
        if done:
            script.index += 1
            script.frame_in_action = 0

    # -- pointer actions ----------------------------------------------------------------------------

    @staticmethod
    def _target_point(state, label: str, fraction: float = 0.5) -> tuple[float, float] | None:
        rect = state.rects.get(label)
        if rect is None:
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

    def _drag(self, state, io, action: dict, step: int) -> bool:
        frames = int(action.get("frames", 10))
        f0, f1 = float(action.get("from", 0.5)), float(action.get("to", 0.5))
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
