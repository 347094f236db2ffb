"""cppcheck --enable=all with the MISRA C:2012 addon on the generated .c and .h, every variant.

Every finding must be on the deviation list of docs/codegen.md (:data:`DEVIATIONS`): the
API functions are never called inside the file (``unusedFunction``: the application calls
them), four informational macros of the header are not used by the library (MISRA 2.5:
``<P>_PRESCRIBED_TIME``, ``<P>_RATE_HZ`` and the timing contract's ``<P>_DELAY``,
``<P>_JITTER`` are for the application; ``<P>_PERIOD`` is the step's period check's), and
the spec's ``const`` tables and constants are at file scope although one function reads
each (MISRA 8.9: the spec's numbers stay in one place, one row per line, where a reviewer
reads them).
One bundled case per controller variant (:mod:`hard_helpers`); the cascade's and the
look-ahead's have no circumvent window, so the windowless tables are covered too.
"""

from __future__ import annotations

import re
import shutil

import pytest
from codegen_helpers import misra_findings, write
from hard_helpers import hard_case, variant_params

CPPCHECK = shutil.which("cppcheck")

#: (check id, regular expression on the flagged source line) accepted as deviations.
DEVIATIONS = (
    ("unusedFunction", r"^int \w+_(tube|control|alpha_step|step|virtual_velocity|predict)\("),
    ("misra-c2012-2.5", r"^#define \w+_(PRESCRIBED_TIME|RATE_HZ|DELAY|JITTER) "),
    ("misra-c2012-8.9", r"^static const \w+ [A-Z0-9_]+(\[[A-Z0-9_]+\])? = "),
)


@pytest.mark.skipif(CPPCHECK is None, reason="cppcheck missing: install the Debian package cppcheck")
@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("variant", variant_params())
def test_cppcheck_misra_findings_are_the_listed_deviations(variant, precision, tmp_path):
    case = hard_case(variant)
    prefix = case.prefix
    folder = write(tmp_path, {k: v for k, v in case.files(precision).items()
                              if k in (f"{prefix}.c", f"{prefix}.h")})
    seen = set()
    unused = set()
    for name, line, check, text in misra_findings(CPPCHECK, folder, prefix):
        allowed = [d for d in DEVIATIONS if d[0] == check and re.search(d[1], text)]
        assert allowed, f"{name}:{line}: {check} not on the deviation list: {text!r}"
        seen.add(check)
        if check == "unusedFunction":
            unused.add(re.match(rf"^int {prefix}_(\w+)\(", text).group(1))
    assert seen == {d[0] for d in DEVIATIONS}
    assert unused == set(case.functions)          # the API, and only the API, is unused
