#!/usr/bin/env python3
"""Check that Cargo.toml's `rust-version`, the README and Cargo.lock agree.

The minimum supported Rust of the project is the highest `rust-version` of
the crates Cargo.lock pins (read from the unpacked sources or the index cache
under $CARGO_HOME/registry). Fails when Cargo.toml's `rust-version` is below
it (the lock would not build on that toolchain), when it is above it (the
claim is stricter than needed: say why in Cargo.toml or lower it), or when the
README's "Rust toolchain (X or newer)" differs from Cargo.toml. A pinned crate
whose rust-version cannot be found is listed, not guessed.
"""
import glob
import json
import os
import re
import sys

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
cargo_home = os.environ.get("CARGO_HOME", os.path.expanduser("~/.cargo"))


def ver(s):
    return tuple(int(x) for x in s.split("."))[:3] + (0,) * (3 - len(s.split(".")))


def show(v):
    return ".".join(str(x) for x in v[:2]) + ("" if v[2] == 0 else f".{v[2]}")


def from_source(name, version):
    for f in glob.glob(f"{cargo_home}/registry/src/*/{name}-{version}/Cargo.toml"):
        with open(f, encoding="utf-8") as fh:
            text = fh.read()
        m = re.search(r'^rust-version\s*=\s*"([^"]+)"', text, re.M)
        return m.group(1) if m else ""
    return None


def from_index(name, version):
    n = name.lower()
    sub = {1: "1", 2: "2", 3: f"3/{n[0]}"}.get(len(n), f"{n[:2]}/{n[2:4]}")
    for f in glob.glob(f"{cargo_home}/registry/index/*/.cache/{sub}/{n}"):
        with open(f, "rb") as fh:
            for chunk in fh.read().split(b"\0"):
                if not chunk.startswith(b"{"):
                    continue
                try:
                    entry = json.loads(chunk)
                except ValueError:
                    continue
                if entry.get("vers") == version:
                    return entry.get("rust_version") or ""
    return None


def main():
    lock = open(os.path.join(root, "Cargo.lock"), encoding="utf-8").read()
    packages = re.findall(
        r'\[\[package\]\]\nname = "([^"]+)"\nversion = "([^"]+)"\nsource = "registry',
        lock,
    )
    need, who, unknown = (0, 0, 0), [], []
    for name, version in packages:
        rv = from_source(name, version)
        if rv is None:
            rv = from_index(name, version)
        if rv is None:
            unknown.append(f"{name} {version}")
            continue
        if not rv:
            continue
        v = ver(rv)
        if v > need:
            need, who = v, [f"{name} {version}"]
        elif v == need:
            who.append(f"{name} {version}")
    manifest = open(os.path.join(root, "Cargo.toml"), encoding="utf-8").read()
    m = re.search(r'^rust-version\s*=\s*"([^"]+)"', manifest, re.M)
    declared = ver(m.group(1)) if m else None
    readme = open(os.path.join(root, "README.md"), encoding="utf-8").read()
    r = re.search(r"Rust toolchain \(([0-9.]+) or newer\)", readme)
    said = ver(r.group(1)) if r else None
    print(f"msrv: {len(packages)} locked registry crates; highest rust-version {show(need)} "
          f"({', '.join(who)})")
    if unknown:
        print(f"msrv: rust-version not found for {len(unknown)} crate(s) (not fetched here): "
              + ", ".join(unknown))
    errors = []
    if declared is None:
        errors.append("Cargo.toml has no rust-version")
    elif declared != need:
        errors.append(f"Cargo.toml rust-version {show(declared)} but the lock needs {show(need)}")
    if said is None:
        errors.append('README lacks "Rust toolchain (X or newer)"')
    elif declared is not None and said != declared:
        errors.append(f"README says Rust {show(said)} but Cargo.toml says {show(declared)}")
    for e in errors:
        print(f"msrv: FAIL: {e}")
    if not errors:
        print(f"msrv: ok: Cargo.toml, README and Cargo.lock agree on Rust {show(need)}")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
