#!/usr/bin/env python3
"""test_kernel_order: the kernel files' order is their dependency order.

    test_kernel_order.py ROOT FILE...   (CMakeLists.txt's LSQT_KERNEL_FILES, in order, from ROOT)

The kernels are one translation unit, the files concatenated in the declared order, and
OpenCL C (C99) refuses a call to a function not declared before it. So with no forward
declarations, every call goes to a file earlier in the list (or earlier in its own), the
build checks the order, and no two files call each other. This test fails on a forward
declaration (a prototype ending in ';' outside a body) in any kernel file, and on a file
of kernels/ that the list leaves out."""
import os
import re
import sys

PROTO = re.compile(r"^\s*(?:LSQT_INLINE|LSQT_NOINLINE_CPU|static|inline)\b.*\)\s*$", re.S)


def top_level_statements(text):
    """(line, text) of each statement outside any body that ends in ';', with comments and
    preprocessor lines (and their continuations) removed."""
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    text = re.sub(r"^[ \t]*#(?:[^\n]*\\\n)*[^\n]*", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.M)
    depth, start, line, out = 0, 0, 1, []
    for k, ch in enumerate(text):
        if ch == "\n":
            line += 1
        elif ch == "{":
            if depth == 0:
                start = k + 1
            depth += 1
        elif ch == "}":
            depth -= 1
            if depth == 0:
                start = k + 1
        elif ch == ";" and depth == 0:
            out.append((line, text[start:k]))
            start = k + 1
    return out


def main(root, files):
    bad = []
    files = [os.path.join(root, f) for f in files]
    for f in files:
        for line, stmt in top_level_statements(open(f).read()):
            if PROTO.match(stmt):
                bad.append("%s:%d: forward declaration: %s" % (os.path.relpath(f, root), line, " ".join(stmt.split())))
    listed = {os.path.abspath(f) for f in files}
    kdir = os.path.join(root, "kernels")
    for name in sorted(os.listdir(kdir)):
        if name.endswith(".cl") and os.path.join(kdir, name) not in listed:
            bad.append("kernels/%s: not in LSQT_KERNEL_FILES (CMakeLists.txt)" % name)
    if bad:
        print("test_kernel_order: FAILED:\n  " + "\n  ".join(bad))
        return 1
    print("test_kernel_order: %d files in dependency order, no forward declarations" % len(files))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2:]))
