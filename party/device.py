"""Choosing where Warp kernels run: ``"cpu"`` by default, ``"cuda"`` when asked or found."""

from __future__ import annotations

import os
import re
import sys
import tempfile

import warp as wp

_initialized = False

KNOWN = re.compile(r"cpu|auto|cuda(:[0-9]+)?")
"""Device names party takes."""


def init() -> None:
    """Initialise Warp once, quietly. Warp's native library warns on stderr when a machine has
    no CUDA driver, which is the normal case on a CPU machine; that one line is dropped, any
    other native output is passed on."""
    global _initialized
    if _initialized:
        return
    wp.config.log_level = wp.LOG_WARNING
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as captured:
        os.dup2(captured.fileno(), 2)
        try:
            wp.init()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        captured.seek(0)
        for line in captured.read().decode(errors="replace").splitlines():
            if "Could not find or load the NVIDIA CUDA driver" not in line:
                print(line, file=sys.stderr)
    _initialized = True


def resolve(device: str | None = None) -> str:
    """Return the Warp device name to use.

    ``None`` or ``"auto"`` picks ``$PARTY_DEVICE`` if set, else ``"cuda"`` when a CUDA device
    is present, else ``"cpu"``. ``"cpu"`` and ``"cuda"`` / ``"cuda:N"`` are taken as given;
    any other name is refused."""
    from .errors import InvalidInput

    choice = device or os.environ.get("PARTY_DEVICE") or "auto"
    if not KNOWN.fullmatch(choice):
        source = "--device" if device else "PARTY_DEVICE"
        raise InvalidInput(f"unknown device {choice!r} in {source} (expected cpu, cuda, cuda:N or auto)")
    init()
    if choice == "auto":
        return "cuda" if wp.is_cuda_available() else "cpu"
    if choice.startswith("cuda"):
        if not wp.is_cuda_available():
            raise InvalidInput(f"device {choice!r} requested but no CUDA device is available")
        index = int(choice.partition(":")[2] or 0)
        if index >= wp.get_cuda_device_count():
            raise InvalidInput(f"device {choice!r} requested but this machine has {wp.get_cuda_device_count()} "
                               "CUDA devices")
    return choice
