"""The sample STEP/IGES files ``occsurf inspect`` and ``occsurf check`` read by default (see README.md here),
shipped as package data; ``make_samples.py`` and ``make_holes.py`` wrote them."""
