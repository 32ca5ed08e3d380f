"""Fixtures of the Python package's tests: the program beside the package (SESI_PROGRAM) and the
source tree (SESI_SOURCE_DIR), both set by ctest (tests/python/CMakeLists.txt)."""
import os
import pathlib

import pytest


@pytest.fixture(scope="session")
def program():
    path = os.environ.get("SESI_PROGRAM")
    if not path:
        pytest.skip("SESI_PROGRAM is not set (run through ctest)")
    return str(pathlib.Path(path).resolve())


@pytest.fixture(scope="session")
def source_dir():
    return pathlib.Path(os.environ.get("SESI_SOURCE_DIR", pathlib.Path(__file__).parents[2])).resolve()
