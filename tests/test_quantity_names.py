"""A quantity's name is a member of the generated C structs (sim._ccode), so the declaration
refuses a C keyword by name, where the C compiler would otherwise fail on the generated text."""

import pytest

from acdrive.core._signals import Layout, real


@pytest.mark.parametrize("name", ["register", "default", "volatile", "_Complex"])
def test_a_c_keyword_cannot_name_a_quantity(name):
    with pytest.raises(ValueError, match=f"'{name}' is a C keyword"):
        Layout(real(name, "", "a counter"))


def test_names_that_contain_a_keyword_are_fine():
    assert Layout(real("register_count", "", "a counter"), real("if_a", "A", "a current"))


def test_a_keyword_named_state_would_not_compile():
    """Why the rule exists: the struct member ``double register;`` is a syntax error in C."""
    import shutil
    import subprocess

    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    text = "typedef struct { double register; } s;\n"
    done = subprocess.run([cc, "-std=c99", "-fsyntax-only", "-x", "c", "-"], input=text,
                          capture_output=True, text=True, check=False)  # fmt: skip
    assert done.returncode != 0
