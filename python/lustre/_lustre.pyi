"""Type stubs of the compiled half of the `lustre` package (use `lustre`, not this)."""

import os
from typing import Any

import numpy as np
import numpy.typing as npt

__version__: str

def material_keys() -> list[tuple[str, str, str, list[str]]]: ...
def model_names() -> list[str]: ...
def metal_names() -> list[str]: ...
def wavelength_range_nm() -> tuple[float, float]: ...

class Material:
    def __init__(self, keys_json: str) -> None: ...
    @staticmethod
    def over_file(file_json: str, keys_json: str) -> Material: ...
    @property
    def keys_json(self) -> str: ...
    @property
    def resolved(self) -> str: ...
    def eval(
        self,
        wi: npt.NDArray[np.float64],
        wo: npt.NDArray[np.float64],
        lambda_nm: npt.NDArray[np.float64],
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
    def sample(
        self,
        wi: npt.NDArray[np.float64],
        lambda_nm: npt.NDArray[np.float64],
        u: npt.NDArray[np.float64],
    ) -> tuple[
        npt.NDArray[np.float64],
        npt.NDArray[np.float64],
        npt.NDArray[np.float64],
        npt.NDArray[np.bool_],
    ]: ...
    def specular(
        self, wi: npt.NDArray[np.float64], lambda_nm: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]: ...
    def albedo(
        self, theta_i_deg: npt.NDArray[np.float64], lambda_nm: npt.NDArray[np.float64]
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...

class Scan:
    def __init__(self, heights: npt.NDArray[np.float64], dx: float, dy: float, name: str) -> None: ...
    @property
    def heights(self) -> npt.NDArray[np.float64]: ...
    @property
    def dx(self) -> float: ...
    @property
    def dy(self) -> float: ...
    @property
    def name(self) -> str: ...
    @property
    def format(self) -> str: ...
    @property
    def channel(self) -> tuple[int, str | None]: ...
    @property
    def notes(self) -> list[str]: ...
    def stats_json(self, level: str | None, invalid: str, outliers: str) -> str: ...

def read_scan(
    path: str | os.PathLike[str],
    units: str | None = None,
    format: str | None = None,
    channel: str | None = None,
    pixel_size: tuple[float, float] | None = None,
    size: tuple[float, float] | None = None,
) -> Scan: ...
def fit(
    scan: Scan,
    metal: str,
    model: str,
    cutoff: list[float],
    lambda_nm: float,
    merge_cutoff: float,
    level: str | None,
    invalid: str,
    outliers: str,
    stylus: Scan | None = None,
    stylus_segments: int = 4,
) -> str: ...
def judge(
    scan: Scan,
    metal: str | None,
    lambda_nm: list[float],
    theta_i_deg: list[float],
    cutoff: list[float],
    angles: int,
    tile: int | None,
    crop: int | None,
    upsample: int,
    surrogate: bool,
    level: str | None,
    reference: str | None,
) -> dict[str, Any]: ...
def render(
    path: str | None,
    toml: str | None,
    base_dir: str,
    spp: int | None = None,
    seed: int | None = None,
    threads: int | None = None,
    spectral: int | None = None,
) -> tuple[
    npt.NDArray[np.float32],
    tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]] | None,
]: ...
