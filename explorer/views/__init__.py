"""The views in numpy: their geometry (:mod:`explorer.views.geometry`)."""
