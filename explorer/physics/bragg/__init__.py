"""
Bragg mirrors: Yeh's closed-form reflectance, its spectral landmarks and the piecewise-constant RGB
approximation of Fourneau et al. (2024).

A mirror is ``N`` cells, each a layer of index ``n2`` (thickness ``d2``) followed by a layer of index
``n1`` (thickness ``d1``), between a host medium ``nh`` above and ``n1`` below. With ``nh == n1`` (the
default) this is the paper's mirror (its Figure 2(d)); with ``nh != n1`` the host interface is added
as in its Appendix D, directly above the first ``n2`` layer. ``Lambda = d1 + d2`` and
``delta = d1 / Lambda``.

Angles are given as the cosine of the incidence angle in the host; wavelengths in nanometres;
``omega = 2 pi / lambda`` (rad/nm) is the paper's spectral variable (Section 3.2.1). Waves travel as
``exp(+i k_z z)`` (the ``tmm`` convention; the paper's Eq. 10 is written in the opposite one, which
conjugates amplitudes and leaves reflectances unchanged). Every function here is numpy only and has a
GLSL twin of the same name in ``shaders/lib/bragg.glsl``.

References
----------
Fourneau, Pacanowski, Barla (2024). Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors. Computer Graphics Forum 43(2). Sections 3.1-3.2, Appendices A, B, D.
Yeh (1988). Optical Waves in Layered Media, Chapter 6.

The subpackage by subject (every name is re-exported here, so ``bragg.NAME`` reads the same):

- :mod:`~explorer.physics.bragg.mirror`: the mirror, its constants and the per-angle cell geometry;
- :mod:`~explorer.physics.bragg.reflectance`: Yeh's reflectance (Section 3.1), exact and over many angles and wavelengths;
- :mod:`~explorer.physics.bragg.approximation`: the envelope, the spectral landmarks and the paper's piecewise-constant
  approximation (Sections 3.2.1-3.2.2, Appendix A);
- :mod:`~explorer.physics.bragg.reference`: the converged spectral reference (``reference_rgb``);
- :mod:`~explorer.physics.bragg.windowed`: the converged table's integrand, the fringe average plus the fringes near
  band edges;
- :mod:`~explorer.physics.bragg.band_pieces`: the converged colour by Gauss quadrature over band pieces;
- :mod:`~explorer.physics.bragg.tables`: the tabulated method's converged and draft tables;
- :mod:`~explorer.physics.bragg.textured`: spatially varying mirrors (supplemental Figure 7);
- :mod:`~explorer.physics.bragg.batch`: Yeh's reflectance of many mirrors at once, ``N`` continuous, fringes averaged
  where a coarse sampling would alias them (inverse design's forward model).
"""

from explorer.physics.bragg.approximation import (  # noqa: F401
    FRINGE_B_MIN,
    FRINGE_Q_MIN,
    FRINGE_RESOLVE_NM,
    GROW_EXPONENT,
    MAX_RESOLVED_PIECES,
    N_RESOLVE,
    OMEGA_HIGH,
    OMEGA_LOW,
    RESOLVE_BUDGET,
    SAMPLES_PER_FRINGE,
    _bisect,
    _sub_box,
    airy_point,
    approximate_rgb,
    approximate_xyz_polarised,
    band_edge,
    fringe_average_under_host,
    bloch_phase,
    fringe_count,
    fringe_sharpness,
    fringes_resolved,
    gap_weight,
    host_reflectance,
    mode_frequency,
    mode_range,
    optical_thickness,
    paper_weight,
    pass_band_weight,
    piecewise_constant_boxes,
    reflectance_envelope,
    reflectance_fringe_average,
    subdivisions,
    subdivisions_by_mass,
    subdivisions_resolving_fringes,
    under_host,
    wavelength_of,
    zero_point_after,
)
from explorer.physics.bragg.band_pieces import (  # noqa: F401
    BAND_EDGE_FRINGES,
    COS_SIN_MIN_SIZE,
    DIP_SHARP,
    FRINGE_MEAN_GROWTH,
    FRINGE_MEAN_NM,
    FRINGE_NODES,
    GAP_DECAY,
    GAP_PANELS,
    GAUSS_NODES,
    HOST_FRINGE_MEAN_GROWTH,
    HOST_FRINGE_NODES,
    HOST_SHIFT_STEPS,
    NODE_BLOCK,
    PANEL_NM,
    PIECES_EXACT_N,
    PIECES_MIN_N,
    PIECES_MIN_N_HOST,
    ROOT_GRID,
    ROOT_POLISH,
    ROOT_STEPS,
    _cmf_integral_to,
    _cmf_linear,
    _cmf_nodes,
    _cmf_weighted_sums,
    _cos_sin,
    _gauss_legendre,
    _host_dip,
    _host_line_reflectance,
    _host_slab,
    _line_reflectance,
    _line_reflectance_block,
    _Lines,
    _panels,
    _pieces_xyz,
    _safeguarded_newton,
    band_pieces_rgb,
)
from explorer.physics.bragg.batch import (  # noqa: F401
    BATCH_EDGE,
    absorbing_reflectance_batch,
    bragg_reflectance_batch,
    bragg_reflectance_batch_gradient,
    chebyshev_U_real_N,
)
from explorer.physics.bragg.mirror import (  # noqa: F401
    BISECTION_STEPS,
    COS_THETA_MIN,
    POLARISATIONS,
    WAVELENGTH_HIGH,
    WAVELENGTH_LOW,
    BraggMirror,
    CellGeometry,
    Omega,
    angular_correction,
    cell_geometry,
)
from explorer.physics.bragg.reference import (  # noqa: F401
    _row_spectrum_function,
    _spectra,
    _spectrum_function,
    converged_reflectance_spectra,
    reference_rgb,
    reference_rgb_many,
    substeps_for,
)
from explorer.physics.bragg.reflectance import (  # noqa: F401
    FLOAT32_MAX_N,
    MAX_DECAY,
    ROW_BLOCK,
    _reflectance_real,
    _rows,
    _take,
    airy_slab_coefficients,
    bragg_reflectance,
    chebyshev_U,
    clamp_decay,
    cos_K_Lambda,
    one_minus_exp_minus_2x,
    reflectance_polarised,
    reflectance_spectra,
    reflectance_yeh,
    reflection_coefficient_bragg,
    reflection_coefficient_host,
    slab_coefficients,
)
from explorer.physics.bragg.tables import (  # noqa: F401
    DRAFT_MAX_SUBSTEPS,
    DRAFT_SIZE,
    TABLE_CUBIC_TOLERANCE,
    TABLE_FIRST_SIZE,
    TABLE_MAX_REFINED,
    TABLE_MAX_SIZE,
    TABLE_MAX_SUBSTEPS,
    TABLE_SIZE,
    TABLE_TOLERANCE,
    _cubic_midpoints,
    _interpolation_error_estimate,
    converged_rgb,
    draft_rgb_table,
    tabulated_rgb,
    tabulated_rgb_table,
)
from explorer.physics.bragg.textured import (  # noqa: F401
    TEXTURE_MAPPINGS,
    TEXTURE_TABLE_BUDGET,
    TEXTURE_TABLE_COLUMNS,
    TEXTURE_TABLE_FIRST_ROWS,
    TEXTURE_TABLE_MAX_ROWS,
    TEXTURE_TABLE_ROWS,
    _mirror_rows,
    STRUCTURE_FIELDS,
    _textured_row,
    mapped_mirrors,
    textured_mirror,
    textured_reference_rgb,
    textured_rgb_table,
    textured_tabulated_rgb,
)
from explorer.physics.bragg.windowed import (  # noqa: F401
    EDGE_FRINGES,
    WINDOW_EXACT_SUBSTEPS,
    WINDOW_SUBSTEPS_MIN,
    _windowed_complex,
    _windowed_real,
    edge_window,
    window_threshold,
    windowed_converged_rgb,
    windowed_converged_spectra,
    windowed_spectrum_function,
)
