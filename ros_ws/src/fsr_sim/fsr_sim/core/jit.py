"""How the flight core is compiled: ``numba.njit`` with an on-disk cache that can never serve stale code.

Every per-step function of fsr (plant, rotors, surfaces, disturbances, planner sampling, control laws,
allocation, observer, the lockstep and the in-process loop) is written once, in numba's subset (functions on
floats, tuples and float64 arrays), under a package's ``core/`` folder, and decorated with :data:`jit`:

* compiled: ``numba.njit(cache=True, error_model="numpy", _nrt=False)``, fastmath off, so a compiled run and
  the same source under CPython (``NUMBA_DISABLE_JIT=1``: the decorator then returns the plain function) give
  the same numbers bit for bit. ``error_model="numpy"``: a division by zero gives inf/NaN instead of raising
  (the core checks its singular points itself and returns a status instead of raising);
* without numba's runtime (``_nrt=False``): the core never allocates - every array it works on is made by
  the caller at start-up and outlives the call - so its arrays need no reference counts. With the runtime on,
  numba increments and decrements the count of every array it takes out of the packed parameter and state
  tuples, each an opaque call that also keeps LLVM from holding values in registers across it (measured:
  ex4's closed loop 4.5 -> 0.8 us per step, the controller tick 1.2 -> 0.4 us). The rule that follows for
  core code: no ``np.empty``/``np.zeros``/``.copy()`` and no array-to-array assignment (``a[:] = b`` needs a
  temporary); copy element by element (a scalar fill such as ``a[:] = 0.0`` is fine). Breaking it fails at
  compilation ("NRT required but not enabled"), in ``fsr-compile`` and the tests, never silently;
* cached: compiled machine code is kept in ``<cache>/<key>/<module>/`` where ``<cache>`` is
  ``$FSR_NUMBA_CACHE_BASE`` (or ``$NUMBA_CACHE_DIR``) if set, else ``$XDG_CACHE_HOME/fsr/numba``
  (``~/.cache/fsr/numba``), and ``<key>`` a hash of every source file with compiled functions under the
  ``core/`` folders of the installed fsr packages (:class:`CoreCacheLocator`, placed first in numba's list
  of cache locators; other numba code keeps numba's own). numba's own cache checks only the file of the
  function it loads, not the functions it calls from other files; with the key, any change of any core
  file gives a fresh folder, so a stale cache can only cost a compilation, never a wrong result. The folder
  depends on the sources' content, not on where they are installed, so an editable install, a non-editable
  one and a colcon install of the same code share one cache, and a read-only source tree works the same
  (an unwritable cache folder falls back to one under the temporary directory).

``fsr-compile`` (:mod:`fsr_bringup.cli.compile_cli`, run by ``scripts/setup.sh``) compiles every entry
point once, so that no flight and no node pays a compilation.
"""

from __future__ import annotations

import functools
import hashlib
import os
import sys
import tempfile
from importlib.util import find_spec
from pathlib import Path

CORE_PACKAGES = ("fsr_sim", "fsr_estimation", "fsr_control", "fsr_bringup")  # lowest layer first


def core_sources() -> list[Path]:
    """Every ``core/*.py`` of the installed fsr packages that compiles functions (imports this module), found
    without importing them."""
    files: list[Path] = []
    for name in CORE_PACKAGES:
        spec = find_spec(name)
        for location in (spec.submodule_search_locations or []) if spec is not None else []:
            files += [path for path in sorted((Path(location) / "core").glob("*.py"))
                      if path.name == "jit.py" or "from fsr_sim.core.jit import" in path.read_text(encoding="utf-8")]
    return files


def core_key() -> str:
    """Hash of the core's sources and of the Python version (the cache folder's name; numba checks its own
    version in each cache entry)."""
    digest = hashlib.sha256(sys.version.encode())
    for path in core_sources():
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def _writable(folder: Path) -> bool:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder):
            return True
    except OSError:
        return False


def fsr_cache(name: str) -> Path:
    """``$XDG_CACHE_HOME/fsr/<name>`` (``~/.cache/fsr/<name>``; the temporary directory without a home)."""
    try:
        home_cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    except RuntimeError:  # no home directory
        home_cache = Path(tempfile.gettempdir())
    return home_cache / "fsr" / name


def cache_base() -> Path:
    """The folder that holds one keyed cache folder per version of the core's sources (module docstring)."""
    base = os.environ.get("FSR_NUMBA_CACHE_BASE") or os.environ.get("NUMBA_CACHE_DIR")
    return Path(base) if base else fsr_cache("numba")


def cache_folder(base: Path) -> Path:
    """``base/<key>``, created if missing (a temporary folder if ``base`` cannot be written)."""
    key = core_key()
    folder = base / key
    if not _writable(folder):
        folder = Path(tempfile.gettempdir()) / f"fsr-numba-{os.getuid()}" / key
        folder.mkdir(parents=True, exist_ok=True)
    return folder


CACHE_FOLDER = cache_folder(cache_base())

import numba  # noqa: E402
import numpy  # noqa: E402
from numba.core import caching  # noqa: E402


class CoreCacheLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):  # noqa: SLF001
    """numba cache locator of the core's functions: ``<cache>/<key>/<module>``, whatever the file's path (its
    freshness stamp is numba's hash of the file's content); None for any other function."""

    def __init__(self, py_func: object, py_file: str) -> None:
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._cache_path = str(CACHE_FOLDER / py_func.__module__)

    def get_cache_path(self) -> str:
        return self._cache_path

    @classmethod
    def from_function(cls, py_func: object, py_file: str) -> CoreCacheLocator | None:
        module = getattr(py_func, "__module__", "") or ""
        if not any(module.startswith(f"{package}.core.") for package in CORE_PACKAGES):
            return None
        return super().from_function(py_func, py_file)


caching.CacheImpl._locator_classes.insert(0, CoreCacheLocator)  # noqa: SLF001

jit = functools.partial(numba.njit, cache=True, error_model="numpy", fastmath=False, _nrt=False)
"""The decorator of every core function (module docstring)."""

jit_inline = functools.partial(jit, inline="always")
"""The decorator of core functions that take the packed parameter and state tuples: inlined into their caller
(numba IR), so that the tuples are not copied across a call at every step (measured with numba's runtime on:
the plant's RK4 step 3.0 -> 1.5 us, the whole loop 8 -> 3.6 us per step)."""

prange = numba.prange


def zeroed_record(dtype: numpy.dtype) -> numpy.ndarray:
    """A zeroed 1-element record array of ``dtype``: how the core keeps named state between steps (the plant's
    status, the sensors', the laws' and a sweep's memory). Its fields are read and written in place as
    ``record[0].field``, compiled and under CPython alike (a record array's element has attributes)."""
    return numpy.zeros(1, dtype).view(numpy.recarray)
