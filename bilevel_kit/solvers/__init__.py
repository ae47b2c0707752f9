"""One module (or sub-package) per registered method; :mod:`bilevel_kit.methods` imports
them by name on first use, so importing this package loads no solver back-end.
"""
