"""Pictures of surfaces (course ch. 9 colour-coded curvature, ch. 10 lighting).

* :mod:`.surfaces` — :func:`render_surfaces`, :func:`render_panels`: curvature-coloured PNGs,
  each view rendered offscreen by VTK (:mod:`.vtk_scene`).
"""
