#!/usr/bin/python3
"""Checks that the module layering of docs/design.md is the one CMake enforces.

cmake/aia_module.cmake lists, for each module, the modules it may link
(AIA_LAYERS_<module>); the "Modules" table of docs/design.md says the same in
its "may use" column. Exits 1 and names the difference when they disagree.
"""
import pathlib
import re
import sys

root = pathlib.Path(__file__).resolve().parent.parent
cmake = (root / "cmake/aia_module.cmake").read_text()
design = (root / "docs/design.md").read_text()

enforced = {
    m: set(filter(None, deps.split(";")))
    for m, deps in re.findall(r'set\(AIA_LAYERS_(\w+)\s+"([^"]*)"\)', cmake)
}
documented = {}
for module, uses in re.findall(r"^\| `(\w+)` \| [^|]* \| ([^|]*) \|$", design,
                               re.MULTILINE):
    words = set(re.findall(r"\b[a-z]+\b", re.sub(r"\([^)]*\)", "", uses)))
    if "everything" in words:
        words = set(enforced) - {module}
    documented[module] = words & set(enforced)

problems = []
for module in sorted(set(enforced) | set(documented)):
    if module not in documented:
        problems.append(f"{module}: in cmake/aia_module.cmake, not in docs/design.md")
    elif module not in enforced:
        problems.append(f"{module}: in docs/design.md, not in cmake/aia_module.cmake")
    elif enforced[module] != documented[module]:
        problems.append(f"{module}: cmake allows {sorted(enforced[module])}, "
                        f"docs/design.md says {sorted(documented[module])}")
if problems:
    print("module layering differs:\n  " + "\n  ".join(problems), file=sys.stderr)
    sys.exit(1)
print(f"{len(enforced)} modules: docs/design.md matches cmake/aia_module.cmake")
