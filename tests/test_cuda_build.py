"""Every Warp kernel of the package builds for a CUDA GPU, from the same source that runs on the
CPU: compiled ahead of time to PTX by Warp's NVRTC, which needs no GPU (the CPU-only CI machine
then still catches a kernel that only the CPU back end accepts); and none of them with adjoint
code, which party never uses and which had been most of a cold start's compiling."""

import importlib
import pkgutil

import pytest
import warp as wp

import party

ARCH = 90  # sm_90: the H100/H200 machines the project is measured on


def _kernel_modules() -> list[str]:
    names = [m.name for m in pkgutil.walk_packages(party.__path__, "party.")]
    for name in names:
        importlib.import_module(name)
    return [name for name in names if wp.get_module(name).kernels]


KERNEL_MODULES = _kernel_modules()


def test_the_package_has_kernels_in_every_stage_that_steps():
    for stage in ("party.collision.body", "party.collision.cloth", "party.solvers.explicit.kernels",
                  "party.solvers.implicit.kernels"):
        assert stage in KERNEL_MODULES


@pytest.mark.skipif(wp.get_cuda_toolkit_version() == (0, 0), reason="this Warp build has no CUDA compiler (NVRTC)")
@pytest.mark.parametrize("name", KERNEL_MODULES)
def test_kernels_compile_for_cuda(name, tmp_path):
    wp.compile_aot_module(name, arch=ARCH, module_dir=str(tmp_path), use_ptx=True)
    ptx = list(tmp_path.glob(f"*{name}*.sm{ARCH}.ptx"))
    assert len(ptx) == 1 and ".entry" in ptx[0].read_text()


@pytest.mark.parametrize("name", KERNEL_MODULES)
def test_kernels_compile_without_adjoints(name):
    """A kernel module without ``wp.set_module_options({"enable_backward": False})`` takes Warp's
    default, adjoints on: the whole package then compiled in 68.6 s instead of 24.8 s on an empty
    kernel cache (docs/design.md, Kernels and CPU threads)."""
    assert wp.get_module(name).options["enable_backward"] is False
