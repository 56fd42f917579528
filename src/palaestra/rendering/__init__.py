"""Rendering without pygame: the classic-control scenes, a human window, notebook display.

``palaestra.rendering.scenes`` needs numpy only; the window and notebook helpers import their
optional backends (pygame, matplotlib, IPython, Pillow) when first used.
"""
