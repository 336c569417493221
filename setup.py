from setuptools import setup

setup(
    name="clsamp",
    version="0.1.0",
    description="Sampling patterns for Monte Carlo rendering, generated and measured in OpenCL",
    long_description=open("README.md", encoding="utf-8").read(),
    long_description_content_type="text/markdown",
    python_requires=">=3.10",
    packages=["clsamp", "clsamp.geometry", "clsamp.integrands", "clsamp.runtime", "clsamp.metrics",
              "clsamp.samplers", "clsamp.samplers.ccvt", "clsamp.samplers.poisson_disk", "clsamp.kernels",
              "clsamp.data", "clsamp.scenes"],
    # The OpenCL sources live in kernels/ at the top level and ship inside the package.
    package_dir={"clsamp.kernels": "kernels", "clsamp.scenes": "scenes"},
    package_data={"clsamp.kernels": ["*.cl", "*.h"], "clsamp.data": ["*"], "clsamp.scenes": ["*.json"]},
    include_package_data=False,
    install_requires=[
        "numpy>=1.24",
        "scipy>=1.10",
        "pyopencl>=2024.1",
        "pocl-binary-distribution>=3.0",
        "scikit-image>=0.21",
        "OpenEXR>=3.2",
        "matplotlib>=3.7",
        "tqdm>=4.60",
    ],
    extras_require={
        "test": ["pytest>=7", "hypothesis>=6", "scipy>=1.10", "dask[distributed]>=2024.1"],
        "dask": ["dask[distributed]>=2024.1"],
        "bench": ["scipy>=1.10", "finufft>=2.2", "bridson>=0.1", "qmcpy>=2.0"],
        "docs": ["sphinx>=7", "numpydoc>=1.6", "myst-parser>=2"],
    },
    entry_points={"console_scripts": ["clsamp=clsamp.__main__:entry"]},
)
