"""inserr: error analysis of rotation-modulated ("indexed") strapdown inertial navigation.

The package is organised like a textbook chapter; see ``docs/`` for theory and
conventions. Heavy modules (python-control, matplotlib) are imported only by the
modules that need them.
"""

__version__ = "0.2.0"
