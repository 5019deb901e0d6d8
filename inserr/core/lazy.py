"""Lazy re-exports for package ``__init__`` files (PEP 562 module ``__getattr__``).

A package whose modules need heavy dependencies (scipy, matplotlib, dask, ...)
still offers its main names at package level, but imports the defining module only
when a name is first used, so that importing the package stays cheap.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any


def lazy_exports(
    package: str, names: dict[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """Module ``__getattr__`` and ``__dir__`` that import ``names`` on first use.

    Parameters
    ----------
    package : str
        The package's ``__name__`` (for error messages and caching).
    names : dict
        Exported name -> module that defines it (absolute, e.g.
        ``"inserr.northfinder.study"``).

    Returns
    -------
    __getattr__, __dir__
        To assign in the package's namespace. A name, once imported, is cached in
        the package (``sys.modules[package].__dict__``), so the lookup runs once.
        ``__getattr__.exports`` is the table (read by the layering test).

    Examples
    --------
    In ``inserr/northfinder/__init__.py``::

        __getattr__, __dir__ = lazy_exports(__name__, {"monte_carlo": "inserr.northfinder.study"})
    """
    import sys

    def __getattr__(name: str) -> Any:
        module = names.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(names))

    __getattr__.exports = dict(names)
    return __getattr__, __dir__


def callable_package(package: str, module: str, name: str) -> None:
    """Make the package ``package`` callable: ``package(...)`` runs ``module.name(...)``.

    For the notebook front door, where a subpackage and its main verb share a name
    (``inserr.drift`` is the drift chapter, and ``inserr.drift(scenario, "two-position")``
    runs it). Only the package's own module object changes class (Python allows it
    for modules); ``module`` is imported at the first call, not now.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    module : str
        Module defining the function (inside the package).
    name : str
        The function.
    """
    import sys
    import types

    class CallablePackage(types.ModuleType):
        def __call__(self, *args: Any, **kwargs: Any) -> Any:
            return getattr(importlib.import_module(module), name)(*args, **kwargs)

    CallablePackage.__call__.__doc__ = f"Call :func:`{module}.{name}` (imported on first use)."
    sys.modules[package].__class__ = CallablePackage
