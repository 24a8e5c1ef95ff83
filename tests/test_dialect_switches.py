"""The dialect differences the checker and the API once read from a preset's name are switches of
`Dialect` (st/compiler/dialect.py): each preset sets them as the name test did."""

from __future__ import annotations

import pytest

from st.api import libraries
from st.compiler.dialect import PRESETS
from st.compiler.options import CompileOptions

# switch → the presets it is on in (what `dialect.name == ...` said before)
SWITCHES = {
    "this_as_instance": {"iec"},
    "c_float_arithmetic": {"openplc"},
    "dotted_word_addresses": {"openplc"},
    "matiec_errors": {"openplc"},
    "vendor_library": {"codesys", "twincat"},
}


@pytest.mark.parametrize("switch, on", sorted(SWITCHES.items()))
def test_each_preset_sets_the_switch_as_its_name_did(switch, on):
    assert {name for name, d in PRESETS.items() if getattr(d, switch)} == on


@pytest.mark.parametrize("name", [None, *PRESETS])
def test_the_vendor_library_is_compiled_under_codesys_twincat_and_the_default(name):
    options = CompileOptions(dialect=PRESETS[name]) if name else CompileOptions()
    names = [lib.name for lib in libraries(options)]
    assert ("vendor" in " ".join(names).lower()) == (name in (None, "codesys", "twincat")), names
