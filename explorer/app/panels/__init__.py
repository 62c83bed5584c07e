"""
The app's windows, one module each. A panel is a :class:`~.base.Panel` subclass (its title, where it
docks, what it draws, the GL views it wants advanced); adding one is a new module here,
imported below and listed in :data:`PANELS`.
"""

from explorer.app.panels.base import Panel
from explorer.app.panels.brdf_views import ScatterPanel, SlicePanel
from explorer.app.panels.compare import ComparePanel
from explorer.app.panels.design import DesignPanel
from explorer.app.panels.files import FilesPanel
from explorer.app.panels.inverse import InversePanel
from explorer.app.panels.materials import MaterialsPanel
from explorer.app.panels.parameters import ParametersPanel
from explorer.app.panels.plots import PlotsPanel
from explorer.app.panels.texture import TexturePanel
from explorer.app.panels.polar import PolarPanel
from explorer.app.panels.spectrum import SpectrumPanel
from explorer.app.panels.sphere import SpherePanel
from explorer.app.panels.strips import StripsPanel

#: The windows, in the order they are drawn (a docked window's first tab is the first of its dock here).
PANELS: tuple[type[Panel], ...] = (
    MaterialsPanel, ParametersPanel, FilesPanel, SpherePanel, ComparePanel, SlicePanel, ScatterPanel, SpectrumPanel, PolarPanel,
    StripsPanel, InversePanel, DesignPanel, PlotsPanel, TexturePanel,
)


def dock_layout(imgui, dockspace, panels) -> None:
    """Dock every panel's window where it says (left_top, left, centre, right_top, right_bottom)."""
    internal = imgui.internal
    internal.dock_builder_remove_node(dockspace)
    internal.dock_builder_add_node(dockspace, internal.DockNodeFlagsPrivate_.dock_space)
    internal.dock_builder_set_node_size(dockspace, imgui.get_main_viewport().size)
    split = internal.dock_builder_split_node(dockspace, imgui.Dir.left, 0.26)
    left, rest = split.id_at_dir, split.id_at_opposite_dir
    split = internal.dock_builder_split_node(left, imgui.Dir.up, 0.18)  # the Materials list above the Parameters
    left_top, left = split.id_at_dir, split.id_at_opposite_dir
    split = internal.dock_builder_split_node(rest, imgui.Dir.right, 0.40)
    right, centre = split.id_at_dir, split.id_at_opposite_dir
    split = internal.dock_builder_split_node(right, imgui.Dir.down, 0.45)
    docks = {"left_top": left_top, "left": left, "centre": centre, "right_bottom": split.id_at_dir, "right_top": split.id_at_opposite_dir}
    for panel in panels:
        internal.dock_builder_dock_window(panel.title, docks[panel.dock])
    internal.dock_builder_finish(dockspace)
