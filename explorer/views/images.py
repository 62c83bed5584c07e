"""
Image files of linear RGB renders: ``.png`` (8-bit sRGB with an exposure), ``.npy`` and ``.exr`` (float32
linear), written atomically. Shared by the CLI, the benchmarks and the app's screenshots.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from explorer.errors import OutputError
from explorer.files import atomic_output, check_output as _check_output

__all__ = ["OUTPUT_SUFFIXES", "OVERLAY_RGB", "OutputError", "check_output", "write_image"]

#: What ``render --out`` writes, by suffix.
OUTPUT_SUFFIXES = (".png", ".npy", ".exr")
#: 8-bit colour of the scatter view's circles in PNG output (red, as in the paper's Figure 9).
OVERLAY_RGB = (255, 0, 0)


def check_output(out: Path) -> Path:
    """The directory ``out`` goes to, or :class:`OutputError` before any work is done (:func:`explorer.files.check_output`)."""
    return _check_output(out, OUTPUT_SUFFIXES)


def write_image(image: np.ndarray, out: Path, overlay: np.ndarray | None = None, exposure: float = 1.0,
                tonemap: str = "none") -> None:
    """
    Write a linear RGB image atomically (:func:`explorer.files.atomic_output`): never a partial file.

    Parameters
    ----------
    image : ndarray, HxWx3
        Linear RGB.
    out : Path
        ``.npy``: float32 linear RGB; ``.exr``: OpenEXR, float32 linear RGB (through OpenCV); ``.png``:
        8-bit sRGB of ``tonemap(exposure * image)``.
    overlay : ndarray of bool, HxW, optional
        Pixels painted red in the PNG only (the scatter view's circles).
    exposure : float
        The PNG's multiplier before the sRGB encode, as the app's exposure (linear outputs keep the values).
    tonemap : str
        The PNG's display curve after the exposure (:mod:`explorer.views.tonemap`); ``none`` clamps.
    """
    from explorer.views.tonemap import display_srgb8

    from PIL import Image

    suffix = Path(out).suffix.lower()
    with atomic_output(out, OUTPUT_SUFFIXES) as temporary:
        if suffix == ".exr":
            _write_exr(image, os.fspath(temporary), out)
            return
        with open(temporary, "wb") as stream:
            if suffix == ".npy":
                np.save(stream, np.ascontiguousarray(image, dtype=np.float32))
            else:
                pixels = display_srgb8(image, exposure, tonemap)
                if overlay is not None:
                    pixels[overlay] = OVERLAY_RGB
                Image.fromarray(pixels, mode="RGB").save(stream, format="PNG")


def _write_exr(image: np.ndarray, temporary: str, out: Path) -> None:
    """OpenEXR, 32-bit float RGB, through OpenCV (BGR order) with OpenEXR enabled as for environments."""
    from explorer.views.env import _cv2

    cv2 = _cv2()
    bgr = np.ascontiguousarray(np.asarray(image, dtype=np.float32)[..., ::-1])
    try:
        written = cv2.imwrite(temporary, bgr, [cv2.IMWRITE_EXR_TYPE, cv2.IMWRITE_EXR_TYPE_FLOAT])
    except cv2.error as error:
        raise OSError(0, f"OpenCV: {' '.join(str(error).split())[:200]}") from None
    if not written:
        raise OSError(0, "OpenCV could not write OpenEXR")


#: Image files read as linear RGB as they are (``render``'s float outputs); any other is decoded from sRGB.
LINEAR_INPUT_SUFFIXES = (".npy", ".exr", ".hdr")


def read_linear_image(path) -> np.ndarray:
    """
    An image as linear RGB ``(H, W, 3)`` float64: ``.npy``, ``.exr`` and ``.hdr`` as they are (linear,
    ``render``'s convention), any other image file (PNG, JPEG, TIFF, ...; 8 or 16 bits per channel, grey,
    RGB or RGBA) decoded from sRGB. ``ValueError`` (one line) when it cannot be read.
    """
    file = Path(path)
    if not file.is_file():
        raise ValueError(f"{path}: no such file")
    suffix = file.suffix.lower()
    try:
        if suffix == ".npy":
            image = np.load(file, allow_pickle=False).astype(np.float64)
        elif suffix in LINEAR_INPUT_SUFFIXES:
            image = _opencv_read(file).astype(np.float64)
        else:
            image = _decoded_srgb(file)
    except (OSError, ValueError) as error:
        raise ValueError(f"{path}: cannot read ({' '.join(str(error).split())[:120]})") from None
    if image.ndim != 3 or image.shape[2] < 3 or image.shape[0] < 1 or image.shape[1] < 1:
        raise ValueError(f"{path}: expected an H x W x 3 image, got shape {image.shape}")
    if not np.all(np.isfinite(image[..., :3])):
        raise ValueError(f"{path}: non-finite values")
    return image[..., :3]


def clipped_codes(path) -> np.ndarray | None:
    """
    Where an integer image (PNG, 8 or 16 bits) holds its lowest code (-1) or its highest (+1), per channel
    ``(H, W, 3)`` int8: there the encoding clipped a colour that may lie beyond (a vivid channel below 0 or
    above 1). None for the linear formats (``.npy``, ``.exr``, ``.hdr``), which hold colours exactly.
    """
    file = Path(path)
    if file.suffix.lower() == ".npy" or file.suffix.lower() in LINEAR_INPUT_SUFFIXES:
        return None
    try:
        pixels = _opencv_read(file)
    except OSError:
        from PIL import Image

        with Image.open(file) as picture:
            pixels = np.asarray(picture.convert("RGB"))
    if not np.issubdtype(pixels.dtype, np.integer):
        return None
    pixels = pixels[..., :3]
    top = np.iinfo(pixels.dtype).max
    return (np.where(pixels >= top, 1, 0) - np.where(pixels <= 0, 1, 0)).astype(np.int8)


def _opencv_read(file: Path) -> np.ndarray:
    """The file's pixels as OpenCV decodes them (their depth kept), as RGB (:func:`opencv_rgb`), or OSError."""
    from explorer.views.env import _cv2, opencv_rgb

    cv2 = _cv2()
    try:
        pixels = cv2.imdecode(np.fromfile(file, dtype=np.uint8), cv2.IMREAD_UNCHANGED)
    except cv2.error as error:
        raise OSError(f"OpenCV: {' '.join(str(error).split())[:120]}") from None
    if pixels is None:
        raise OSError("not an image OpenCV can decode")
    return opencv_rgb(pixels)


def _decoded_srgb(file: Path) -> np.ndarray:
    """
    An sRGB image file as linear RGB: integers scaled by their depth's maximum (a 16-bit PNG is not
    clipped to 8 bits), then the sRGB decoding; what OpenCV cannot decode, Pillow reads as 8-bit RGB.
    """
    import colour

    try:
        pixels = _opencv_read(file)
    except OSError:
        from PIL import Image

        with Image.open(file) as picture:
            pixels = np.asarray(picture.convert("RGB"))
    if not np.issubdtype(pixels.dtype, np.integer):
        raise ValueError(f"{pixels.dtype} pixels in an sRGB image (linear floats go in .exr or .npy)")
    encoded = pixels.astype(np.float64) / np.iinfo(pixels.dtype).max
    return np.asarray(colour.cctf_decoding(encoded, function="sRGB"))
