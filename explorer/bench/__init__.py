"""
Benchmarks and accuracy studies, one module per study; every name is re-exported here, so ``bench.NAME`` reads the
same:

- :mod:`~explorer.bench.common`: what the studies share (figure output, the grids, progress lines);
- :mod:`~explorer.bench.table1`: ``bench``, the paper's Table 1 on this machine;
- :mod:`~explorer.bench.figure4`: ``accuracy``, the Figure 4 grid and its strips;
- :mod:`~explorer.bench.thin_film`: ``bench --thin-film``;
- :mod:`~explorer.bench.layers`: ``bench --layers``, rough layers and layered stacks;
- :mod:`~explorer.bench.app`: ``bench --app``, the explorer's frame times;
- :mod:`~explorer.bench.position_free`: ``bench --position-free``;
- :mod:`~explorer.bench.tables`: ``bench --tables``, host table rebuilds and the tabulated method's cost;
- :mod:`~explorer.bench.scaling`: ``bench --scaling``, how the table and the shading cost grow with ``N``;
- :mod:`~explorer.bench.markdown_tables`: their documents as the Markdown tables of ``--markdown`` and
  ``docs/validation.md``.

The commands (``bench``, ``accuracy``: :mod:`explorer.cli.commands`) parse their options and call these; the
checkout's scripts (:mod:`explorer.dev.validation_doc`) call them without the command line.

``bench --design`` lives with the design command (:mod:`explorer.cli.design`), ``bench --mitsuba`` with the plugins
(:mod:`explorer.mitsuba.bench`).
"""

from explorer.bench.app import (  # noqa: F401
    APP_ENV_MATERIAL,
    APP_ENV_SLIDER,
    APP_ENV_VALUES,
    APP_GOAL_FIRST_PASS_MS,
    APP_GOAL_FPS,
    APP_MESH_CASES,
    APP_METHODS,
    APP_MODES,
    _app_session,
    _drag,
    _frame_row,
    app_bench_script,
    app_env_script,
    app_mesh_steps,
    app_view_cases,
    app_view_steps,
    print_view_frames,
    run_app_bench,
    summarise_app_frames,
    summarise_env_frames,
    summarise_mesh_frames,
    summarise_view_frames,
)
from explorer.bench.common import (  # noqa: F401
    BENCH_LAMBDAS,
    FIGURE4_DELTAS,
    FIGURE4_LAMBDAS,
    FIGURE_SUFFIXES,
    STRIP_SUFFIXES,
    THETA_DEGREES,
    _progress,
    save_figure,
)
from explorer.bench.figure4 import (  # noqa: F401
    figure4_accuracy,
    figure4_strips,
    plot_accuracy,
    run_accuracy,
)
from explorer.bench.layers import (  # noqa: F401
    FIGURE8_LAYER,
    LAYER_ALPHAS,
    LAYER_GOALS,
    LAYER_PAPER,
    SLICE_LUMINANCE_THRESHOLD,
    SLICE_METHODS,
    STACK_PAIRS,
    STACK_PRESETS,
    format_layers,
    run_layers_bench,
    slice_accuracy,
    stack_study,
)
from explorer.bench.position_free import (  # noqa: F401
    POSITION_FREE_CASES,
    POSITION_FREE_GOAL_S,
    POSITION_FREE_TARGET,
    POSITION_FREE_THETA,
    _cpu_seconds,
    run_position_free_bench,
)
from explorer.bench.scaling import (  # noqa: F401
    SCALING_ANGLES,
    SCALING_N,
    SCALING_SPHERES,
    _converged_rule_rgb,
    plot_scaling,
    run_scaling_bench,
    scaling_study,
)
from explorer.bench.table1 import (  # noqa: F401
    _accuracy,
    _methods,
    delta_E_over_theta,
    format_table,
    run_bench,
    table_rebuild_ms,
)
from explorer.bench.tables import (  # noqa: F401
    TABLES_LAMBDA_STEP,
    TABLES_MIRROR,
    TABLES_N,
    _medians,
    _timed_frame,
    _timed_ms,
    run_tables_bench,
    table_timings,
    tabulated_over_schlick,
)
from explorer.bench.thin_film import (  # noqa: F401
    THIN_FILM_METHODS,
    format_thin_film,
    run_thin_film_bench,
    thin_film_accuracy,
)
