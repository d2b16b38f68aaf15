"""The library packages export their public API lazily (PEP 562): `__all__` is what their `if TYPE_CHECKING:` imports
name, every name resolves to its submodule's object on first access, and importing a package loads none of them."""

import importlib
import subprocess
import sys

import pytest

from trajectories.lazy import type_checking_imports

PACKAGES = ("planners", "trajectories", "tracking")


@pytest.mark.parametrize("name", PACKAGES)
def test_all_is_what_the_type_checking_imports_name_and_each_resolves(name):
    package = importlib.import_module(name)
    table = type_checking_imports(package.__file__)
    assert sorted(package.__all__) == sorted(table) and len(set(package.__all__)) == len(package.__all__)
    for exported, (submodule, attribute) in table.items():
        assert getattr(package, exported) is getattr(importlib.import_module(f"{name}.{submodule}"), attribute)
    assert set(package.__all__) <= set(dir(package))
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        package.not_a_name  # noqa: B018


def test_importing_a_package_loads_none_of_its_modules():
    code = (
        "import sys, planners, trajectories, tracking; "
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('planners', 'trajectories', 'tracking')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert eval(out) == ["planners", "tracking", "trajectories", "trajectories.lazy"]
