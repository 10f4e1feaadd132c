"""Pictures of surfaces (course ch. 9 colour-coded curvature, ch. 10 lighting).

* :mod:`.surfaces` — :func:`render_surfaces`: curvature-coloured, Lambert-shaded PNGs.
"""
