"""lustre: spectral BRDFs of measured metal surfaces, from Python.

Numpy in, numpy out. Every function calls the library function the ``lustre`` command
line calls for the same job, so the numbers equal the CLI's to the last bit:

>>> import numpy as np, lustre
>>> m = lustre.Material(model="ghs", sigma_um=0.138, lc_um=2.0, gamma=2.0, metal="cu")
>>> wi = np.array([[0.5, 0.0, 0.75 ** 0.5]])
>>> f, pdf = m.eval(wi, wi * [-1, -1, 1], 550.0)
>>> scan = lustre.read_scan("data/surfaces/di-3.di")
>>> stats = scan.stats()                  # the dict `lustre fit stats --json` prints
>>> material = lustre.fit(scan, metal="cu")   # the material file as a dict
>>> report = lustre.judge(scan, metal="cu")   # the dict `lustre judge --json` prints
>>> img = lustre.render("scenes/default.toml", spp=4)   # (H, W, 3) float32, linear sRGB

Directions are unit vectors in the local shading frame (normal +z), both pointing away
from the surface (physics.md §1). Wavelengths are in nm, lengths of scans in metres.
Errors are ``ValueError`` (a bad key, value or file content; the message names it) and
``OSError`` (a file that cannot be read).
"""

from __future__ import annotations

import json
import math
import os
from typing import Any, Mapping, Sequence

import numpy as np

from . import _lustre

__version__: str = _lustre.__version__
__all__ = [
    "Material",
    "Scan",
    "read_scan",
    "fit",
    "judge",
    "render",
    "material_keys",
    "model_names",
    "metal_names",
]


def material_keys() -> list[tuple[str, str, str, list[str]]]:
    """Every material key as ``(key, type, documentation, models that read it)``.

    An empty model list means every model reads the key (``model`` and the index keys
    ``metal``, ``nk``, ``nk_csv``, ``fresnel``) or none but the resolution of an
    ``include`` (``include``, ``cutoff``). The table is the library's own
    (``brdf::spec::MaterialDesc``), the one scene files and ``lustre brdf eval`` read.
    """
    return _lustre.material_keys()


def model_names() -> list[str]:
    """The values ``model`` accepts."""
    return _lustre.model_names()


def metal_names() -> list[str]:
    """The built-in metals ``metal`` accepts (aliases such as ``copper`` work too)."""
    return _lustre.metal_names()


def _keys_doc() -> str:
    lines = []
    for key, ty, doc, models in material_keys():
        used = ", ".join(models) if models else "all models"
        lines.append(f"    {key} ({ty}; {used})\n        {doc}")
    return "\n".join(lines)


def _rows(a: Any, name: str) -> np.ndarray:
    """An (N, 3) C-contiguous float64 array (a single direction becomes one row)."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    if a.ndim == 1:
        a = a.reshape(1, -1)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name}: expected an array of shape (N, 3), got {a.shape}")
    return a


def _vector(a: Any, name: str) -> np.ndarray:
    """A 1-D C-contiguous float64 array (a scalar becomes one element)."""
    a = np.ascontiguousarray(np.atleast_1d(np.asarray(a, dtype=np.float64)))
    if a.ndim != 1:
        raise ValueError(f"{name}: expected a number or a 1-D array, got shape {a.shape}")
    return a


def _nan_to_none(v: Any) -> Any:
    """JSON has no NaN: a material file's undefined diagnostics travel as null."""
    if isinstance(v, float) and math.isnan(v):
        return None
    if isinstance(v, Mapping):
        return {k: _nan_to_none(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_nan_to_none(x) for x in v]
    return v


class Material:
    __doc__ = f"""A reflection model built from the flat material keys.

    ``Material(**keys)`` takes the keys of a scene's ``[materials.NAME]`` table, a
    ``lustre brdf eval`` line and a ``lustre fit`` material file: every model and option.
    ``include``, ``nk_csv`` and ``psd_csv`` name files relative to the working directory.
    A key the model does not read, or a bad value, raises ``ValueError`` naming the key.

    Keys (type; the models that read it):

{_keys_doc()}

    Methods take arrays of N rows and release the GIL; large arrays are spread over all
    cores. ``lambda_nm`` is one wavelength [nm] or one per row; a single row of ``wi``,
    ``wo`` or ``u`` is used for every row.
    """

    def __init__(self, **keys: Any) -> None:
        try:
            text = json.dumps(keys, allow_nan=False)
        except ValueError as e:
            raise ValueError(f"material keys must be finite numbers: {e}") from None
        except TypeError as e:
            raise ValueError(f"material keys must be numbers, strings or lists: {e}") from None
        self._m = _lustre.Material(text)
        self._keys = dict(keys)

    @classmethod
    def from_fit(cls, material_file: Mapping[str, Any], **overrides: Any) -> "Material":
        """The material of a :func:`fit` result (or a parsed material file).

        Built as a scene's ``include`` of that file builds it, by the same code: the
        file's ``[material]`` under ``overrides`` (e.g. ``model="ggx"``, or
        ``model="two_scale", cutoff="cutoff_100"`` for a split), and for
        ``model="measured_psd"`` (or its stretched forms) the file's own ``[psd]``
        table. Raises ``ValueError`` naming the key, as an include would. Its
        :attr:`keys` are the resolved flat keys (a measured PSD stays in the file).
        """
        try:
            file_text = json.dumps(_nan_to_none(dict(material_file)), allow_nan=False)
            keys_text = json.dumps(overrides, allow_nan=False)
        except (TypeError, ValueError) as e:
            raise ValueError(f"material file and keys must be JSON-like: {e}") from None
        m = cls.__new__(cls)
        m._m = _lustre.Material.over_file(file_text, keys_text)
        m._keys = json.loads(m._m.keys_json)
        return m

    @property
    def keys(self) -> dict[str, Any]:
        """The keys the material was built from."""
        return dict(self._keys)

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self._keys.items())
        return f"lustre.Material({args})"

    def eval(self, wi: Any, wo: Any, lambda_nm: Any) -> tuple[np.ndarray, np.ndarray]:
        """``(f, pdf)``: the glossy BRDF [1/sr] and the sampling pdf of ``wo`` [1/sr].

        ``wi``, ``wo``: (N, 3) unit directions in the local frame. ``f`` excludes the
        specular delta lobe (see :meth:`specular`); both are (N,) float64, the numbers
        ``lustre brdf eval`` prints as ``f`` and ``pdf``.
        """
        return self._m.eval(_rows(wi, "wi"), _rows(wo, "wo"), _vector(lambda_nm, "lambda_nm"))

    def sample(
        self, wi: Any, lambda_nm: Any, u: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(wo, pdf, weight, is_delta)`` sampled with the random numbers ``u``.

        ``u``: (N, 3) in [0, 1). ``wo`` (N, 3); ``pdf`` the solid-angle pdf of a glossy
        sample (the lobe choice included) or the discrete probability of a delta one;
        ``weight`` = f·cosθo/pdf (glossy) or the delta weight over its probability;
        ``is_delta`` (N,) bool. A row that cannot be sampled has ``wo`` = 0 and weight 0.
        """
        return self._m.sample(_rows(wi, "wi"), _vector(lambda_nm, "lambda_nm"), _rows(u, "u"))

    def specular(self, wi: Any, lambda_nm: Any) -> np.ndarray:
        """(N,) weight of the specular delta lobe (``specular_weight`` of ``brdf eval``)."""
        return self._m.specular(_rows(wi, "wi"), _vector(lambda_nm, "lambda_nm"))

    def albedo(self, theta_i_deg: Any, lambda_nm: Any, parts: bool = False) -> Any:
        """Directional albedo at incidence ``theta_i_deg`` (degrees, azimuth 0).

        By the adaptive hemispherical quadrature ``lustre brdf plot`` uses. Returns the
        total (N,) array, or with ``parts=True`` the pair ``(scattered, specular)``.
        """
        s, d = self._m.albedo(_vector(theta_i_deg, "theta_i_deg"), _vector(lambda_nm, "lambda_nm"))
        return (s, d) if parts else s + d


class Scan:
    """A height map or profile [m] and where it came from.

    ``Scan(heights, dx, dy=None, name="<array>")`` wraps an (ny, nx) array of heights in
    metres (a profile: shape (nx,) or (1, nx); NaN marks invalid points) with its pixel
    spacings in metres, so SurfaceTopography or Gwyddion users hand over what they
    loaded. :func:`read_scan` reads a file.
    """

    def __init__(self, heights: Any, dx: float, dy: float | None = None, name: str = "<array>") -> None:
        h = np.asarray(heights, dtype=np.float64)
        if h.ndim == 1:
            h = h.reshape(1, -1)
        if h.ndim != 2:
            raise ValueError(f"heights: expected a 2-D (ny, nx) or 1-D array, got shape {h.shape}")
        self._s = _lustre.Scan(np.ascontiguousarray(h), float(dx), float(dx if dy is None else dy), name)

    @classmethod
    def _wrap(cls, s: Any) -> "Scan":
        obj = cls.__new__(cls)
        obj._s = s
        return obj

    @property
    def heights(self) -> np.ndarray:
        """Heights [m], (ny, nx) float64 (a profile has ny == 1), NaN where invalid."""
        return self._s.heights

    @property
    def dx(self) -> float:
        """Pixel spacing along x [m]."""
        return self._s.dx

    @property
    def dy(self) -> float:
        """Pixel spacing along y [m] (``dx`` for a profile)."""
        return self._s.dy

    @property
    def name(self) -> str:
        """The file as named, or the name given to the array."""
        return self._s.name

    @property
    def format(self) -> str:
        """The reader used (``array`` for an array)."""
        return self._s.format

    @property
    def channel(self) -> tuple[int, str | None]:
        """``(index, name)`` of the channel read."""
        return self._s.channel

    @property
    def notes(self) -> list[str]:
        """What the reader noted (assumed units, resampling, flags used)."""
        return self._s.notes

    def __repr__(self) -> str:
        return repr(self._s)

    def stats(
        self, level: str | None = None, invalid: str = "refuse", outliers: str = "flag"
    ) -> dict[str, Any]:
        """The dict ``lustre fit stats --json`` prints.

        ``level``: ``none``, ``line``, ``plane``, ``poly2``, ``poly3`` (default: a plane
        for maps, a line for profiles); ``invalid``: ``refuse``, ``crop`` or ``fill`` a
        mostly invalid scan; ``outliers``: ``flag`` or ``mask`` spikes. Lengths in metres;
        the ``warnings`` list says what to distrust.
        """
        return json.loads(self._s.stats_json(level, invalid, outliers))


def read_scan(
    path: str | os.PathLike[str] | Any,
    units: str | None = None,
    format: str | None = None,
    channel: int | str | None = None,
    pixel_size: float | tuple[float, float] | None = None,
    size: float | tuple[float, float] | None = None,
    dx: float | None = None,
    dy: float | None = None,
) -> Scan:
    """Reads a scan file as ``lustre fit`` does, or wraps an array.

    ``units`` (``"um"`` or ``"um,nm"`` for lengths,heights), ``format``, ``channel``
    (index or name), ``pixel_size`` and ``size`` (metres; one value or (x, y)) are the
    CLI's ``--units``, ``--format``, ``--channel``, ``--pixel-size``, ``--size``. Given a
    numpy array instead of a path, returns ``Scan(path, dx, dy)``.
    """
    if isinstance(path, np.ndarray):
        if dx is None:
            raise ValueError("dx: give the pixel spacing [m] of the array")
        return Scan(path, dx, dy)

    def pair(v: Any) -> tuple[float, float] | None:
        if v is None:
            return None
        if isinstance(v, (int, float)):
            return (float(v), float(v))
        a, b = v
        return (float(a), float(b))

    ch = None if channel is None else str(channel)
    return Scan._wrap(
        _lustre.read_scan(os.fspath(path), units, format, ch, pair(pixel_size), pair(size))
    )


def _scan(scan: Scan | str | os.PathLike[str]) -> Any:
    if isinstance(scan, Scan):
        return scan._s
    return read_scan(scan)._s


def fit(
    scan: Scan | str | os.PathLike[str],
    metal: str = "stainless_steel",
    model: str = "auto",
    cutoff: Sequence[float] = (50.0, 100.0, 150.0),
    lambda_nm: float = 550.0,
    merge_cutoff: float = 1.0,
    level: str | None = None,
    invalid: str = "refuse",
    outliers: str = "flag",
    stylus: Scan | str | os.PathLike[str] | None = None,
    stylus_segments: int = 4,
) -> dict[str, Any]:
    """The material file ``lustre fit`` writes, as a dict with the TOML's keys.

    The options are the CLI's flags (``--metal``, ``--model``, ``--cutoff`` as multiples
    of ``lambda_nm``, ``--merge-cutoff`` in rad/µm, ``--level``, ``--invalid``,
    ``--outliers``, ``--stylus``, ``--stylus-segments``). ``Material.from_fit(fit(...))``
    builds the chosen model. Raises ``ValueError`` for a scan the fit refuses.
    """
    st = None if stylus is None else _scan(stylus)
    text = _lustre.fit(
        _scan(scan), metal, model, [float(c) for c in cutoff], float(lambda_nm),
        float(merge_cutoff), level, invalid, outliers, st, int(stylus_segments),
    )
    return json.loads(text)


def judge(
    scan: Scan | str | os.PathLike[str],
    metal: str | None = None,
    lambda_nm: Sequence[float] = (450.0, 550.0, 650.0),
    theta_i_deg: Sequence[float] = (0.0, 45.0, 80.0),
    cutoff: Sequence[float] = (50.0, 100.0, 150.0),
    angles: int = 90,
    tile: int | None = None,
    crop: int | None = None,
    upsample: int = 1,
    surrogate: bool = True,
    level: str | None = None,
    reference: str | os.PathLike[str] | None = None,
) -> dict[str, Any]:
    """The dict ``lustre judge --json`` prints: every model ranked against the
    explicit BRDF of the scan's own heights.

    The options are the CLI's flags (``--metal``, ``--lambda``, ``--theta-i``,
    ``--cutoff``, ``--angles``, ``--tile``, ``--crop``, ``--upsample``,
    ``--no-surrogate`` as ``surrogate=False``, ``--level``, ``--reference``). Takes a
    minute or more on a full scan; ``crop`` and ``surrogate=False`` shorten it.
    """
    ref = None if reference is None else os.fspath(reference)
    return _lustre.judge(
        _scan(scan), metal, [float(x) for x in lambda_nm], [float(x) for x in theta_i_deg],
        [float(x) for x in cutoff], int(angles), tile, crop, int(upsample), bool(surrogate),
        level, ref,
    )


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        if not math.isfinite(v):
            raise ValueError(f"scene values must be finite, got {v}")
        return repr(float(v))
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, Mapping):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise ValueError(f"scene value {v!r}: not a number, string, list or table")


def _toml(d: Mapping[str, Any], prefix: str = "") -> str:
    """TOML text of a scene dict: plain keys first, then each table under its header."""
    plain = [(k, v) for k, v in d.items() if not isinstance(v, Mapping)]
    tables = [(k, v) for k, v in d.items() if isinstance(v, Mapping)]
    out = [f"{json.dumps(str(k))} = {_toml_value(v)}" for k, v in plain]
    for k, v in tables:
        name = f"{prefix}{json.dumps(str(k))}"
        out.append(f"\n[{name}]")
        out.append(_toml(v, name + "."))
    return "\n".join(out)


def render(
    scene: str | os.PathLike[str] | Mapping[str, Any],
    spp: int | None = None,
    seed: int | None = None,
    threads: int | None = None,
    base_dir: str | os.PathLike[str] = ".",
    spectral: int | None = None,
) -> Any:
    """Renders a scene as ``lustre render`` does: (H, W, 3) float32 linear sRGB.

    ``scene``: a scene file, or the same scene as a dict (the TOML's tables as nested
    dicts; its relative file names are read relative to ``base_dir``). ``spp`` defaults
    to the scene's; ``threads`` to every core. Nothing is written to disk.

    ``spectral=N`` (as ``lustre render --spectral N``, 1..=256) returns
    ``(rgb, bands, bounds_nm)``: ``bands`` (H, W, N) float64, the mean spectral radiance
    in each of N equal bands over 360–830 nm (no exposure applied), ``bounds_nm`` their
    N + 1 edges. A render with bands samples its wavelengths at every bounce, so its RGB
    differs from a render without (by noise only).
    """
    if isinstance(scene, Mapping):
        path, text = None, _toml(scene)
    else:
        path, text = os.fspath(scene), None
    rgb, bands = _lustre.render(path, text, os.fspath(base_dir), spp, seed, threads, spectral)
    if spectral is None:
        return rgb
    cube, bounds = bands
    return rgb, cube, bounds
