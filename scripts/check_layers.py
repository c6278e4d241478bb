#!/usr/bin/env python3
"""The folders are the architecture: checks that every #include follows it.

core/ is in layers, each including only itself and those below it (core/include/gwnrt/L and
core/src/L alike):

    base < geometry < io < field < trace < sdf < model < query < meshing

Around core, each top-level folder includes only the folders listed for it below (gwnrt/...
headers of the libraries it links, and root-relative paths such as "apps/common/program.h").
Prints every include that breaks a rule and exits 1; exits 0 when there is none.
"""
import pathlib
import re
import subprocess
import sys

CORE_LAYERS = ["base", "geometry", "io", "field", "trace", "sdf", "model", "query", "meshing"]

# Top-level folder -> what its files may include: "core" (any gwnrt/<layer>/ header), "cuda"
# (gwnrt/cuda.h), "engine" (gwnrt/engine.h), "embree" (gwnrt/embree.h), or another top-level
# folder by its root path. Only cuda/ and engine/ choose the device; the rest ask the engine.
ALLOWED = {
    "cuda": {"core", "cuda"},
    "engine": {"core", "cuda", "engine"},
    "plugin": {"core", "embree"},
    "python": {"core", "engine"},
    "reference": {"core", "reference"},
    # render/'s kernel file reads gwnrt/cuda.h; its host code reaches the GPU through the engine.
    "render": {"core", "cuda", "engine", "embree", "render", "apps"},
    "apps": {"core", "engine", "apps", "render", "reference"},
    "bench": {"core", "engine", "apps", "render", "reference"},
    "examples": {"core", "cuda", "engine", "embree"},
    "tests": {"core", "cuda", "engine", "embree", "apps", "render", "reference", "tests"},
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def core_layer(path):
    """The layer of a core file, from core/include/gwnrt/<layer>/ or core/src/<layer>/."""
    parts = path.parts
    if parts[:3] == ("core", "include", "gwnrt") and len(parts) > 4:
        return parts[3]
    if parts[:2] == ("core", "src") and len(parts) > 3:
        return parts[2]
    return None


def included_kind(name):
    """What an include names: ("core", layer), ("cuda",), ("embree",), ("folder", top) or None
    for a file beside the includer (resolved by the compiler relative to it)."""
    if name.startswith("gwnrt/"):
        rest = name[len("gwnrt/"):]
        if rest == "cuda.h":
            return ("cuda", None)
        if rest == "embree.h":
            return ("embree", None)
        if rest == "engine.h":
            return ("engine", None)
        return ("core", rest.split("/")[0])
    top = name.split("/")[0]
    if top in ALLOWED or top == "core":
        return ("folder", top)
    return None


def check(root, path, problems):
    """The includes of `path` (relative to the tree's `root`) against the rules."""
    top = path.parts[0]
    layer = core_layer(path)
    for number, line in enumerate((root / path).read_text(encoding="utf-8").splitlines(), 1):
        m = INCLUDE.match(line)
        if not m:
            continue
        name = m.group(1)
        if name.startswith("../"):
            problems.append(f"{path}:{number}: {name}: includes a parent folder's file")
            continue
        kind, what = included_kind(name) or (None, None)
        if top == "core":
            # core/src's private headers are named from core/src: "base/message.h", "io/text.h".
            if kind == "core" or (kind is None and "/" in name):
                target = what if kind == "core" else name.split("/")[0]
                if target not in CORE_LAYERS:
                    problems.append(f"{path}:{number}: {name}: not a core layer")
                elif layer is None or CORE_LAYERS.index(target) > CORE_LAYERS.index(layer):
                    problems.append(f"{path}:{number}: {name}: layer '{layer}' includes '{target}', a layer above it")
            elif kind is not None:
                problems.append(f"{path}:{number}: {name}: core includes only core")
            continue
        allowed = ALLOWED.get(top)
        if allowed is None or kind is None:
            continue
        key = what if kind == "folder" else kind
        if key not in allowed:
            problems.append(f"{path}:{number}: {name}: {top}/ does not include {key}")


def main():
    root = pathlib.Path(__file__).resolve().parent.parent
    files = subprocess.run(["git", "ls-files", "*.h", "*.cpp", "*.cu", "*.cuh"], cwd=root, check=True,
                           capture_output=True, text=True).stdout.split()
    problems = []
    for f in files:
        check(root, pathlib.Path(f), problems)
    for p in problems:
        print(p)
    print(f"check layers: {len(files)} files, {len(problems)} includes against the layout")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
