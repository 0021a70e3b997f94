#!/usr/bin/python3
"""Checks that the documentation matches the code it names.

    tools/check_docs.py AIA [FILE.md ...]

With no files: README.md, docs/*.md and docs/notes/*.md (the test suite runs
this, tests/CMakeLists.txt: docs.commands_and_links). Two checks:

1. Every `aia COMMAND` named in code (inline code spans and shell code
   blocks: ```, ```sh, ```bash, ```console) is a command of the binary AIA:
   `AIA COMMAND --help` exits 0 and prints `Usage: ... COMMAND`. (CLI11
   answers `aia nosuch --help` with the top-level help and exit 0, so the exit
   status alone would not do.)
2. Every relative link, `[text](path)` or `![alt](path)` outside code, names
   a file or folder that exists inside the repository (relative to the
   Markdown file), and a `#fragment` on a Markdown file names one of its
   headings (GitHub's anchors: lower case, punctuation dropped, spaces to
   dashes). A code span that is a relative path to a Markdown file
   starting with `../` must name one inside the repository too.

Each problem is printed as FILE:LINE: what is wrong; the exit status is 1 when
there is any, 2 on bad usage.
"""
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
SHELL_FENCES = {"", "sh", "bash", "shell", "console"}
# `aia WORD`: aia as a word (also build/aia, "$aia"), then a command word.
# Not aia::, aia.x, aia_x, aia/x, import aia.
COMMAND = re.compile(
    r"(?:^|(?<=[\s/\"'`($]))aia[\"']?[ \t]+([a-z][a-z0-9_-]*)")
LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
CODE_SPAN = re.compile(r"(`+)(.+?)\1")
FENCE = re.compile(r"^\s*(```+|~~~+)\s*([A-Za-z0-9_+-]*)")


def default_files():
    files = [os.path.join(ROOT, "README.md")]
    for folder in ("docs", os.path.join("docs", "notes")):
        path = os.path.join(ROOT, folder)
        if os.path.isdir(path):
            files += sorted(
                os.path.join(path, f) for f in os.listdir(path)
                if f.endswith(".md"))
    return files


def scan(path):
    """Yields (line number, kind, text): kind "code" for shell code (a fenced
    block's line or an inline code span), "prose" for a line outside code
    with its code spans removed."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    fence = None  # (marker, shell?) inside a fenced block
    for number, line in enumerate(lines, 1):
        m = FENCE.match(line)
        if fence is None and m:
            fence = (m.group(1), m.group(2).lower() in SHELL_FENCES)
            continue
        if fence is not None:
            if m and m.group(1).startswith(fence[0]) and not m.group(2):
                fence = None
            elif fence[1]:
                yield number, "code", line
            continue
        for span in CODE_SPAN.finditer(line):
            yield number, "code", span.group(2)
        yield number, "prose", CODE_SPAN.sub("", line)


def command_of(aia, word, cache):
    if word not in cache:
        try:
            out = subprocess.run([aia, word, "--help"], capture_output=True,
                                 text=True, timeout=60)
            usage = re.search(r"^Usage: \S+ " + re.escape(word) + r"\b",
                              out.stdout, re.M)
            cache[word] = out.returncode == 0 and usage is not None
        except (OSError, subprocess.TimeoutExpired):
            cache[word] = False
    return cache[word]


def slug(heading):
    text = re.sub(r"[`*_]|<[^>]*>", "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path, cache):
    if path not in cache:
        seen = {}
        names = set()
        in_fence = False
        with open(path, encoding="utf-8") as f:
            for line in f:
                if FENCE.match(line):
                    in_fence = not in_fence
                    continue
                m = None if in_fence else re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$",
                                                   line)
                if m:
                    base = slug(m.group(1))
                    n = seen.get(base, 0)
                    seen[base] = n + 1
                    names.add(base if n == 0 else "%s-%d" % (base, n))
        cache[path] = names
    return cache[path]


def main(argv):
    if len(argv) >= 2 and argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0
    if len(argv) < 2:
        print(__doc__.strip().split("\n\n")[1], file=sys.stderr)
        return 2
    aia = argv[1]
    if not os.access(aia, os.X_OK):
        print("error: %s: not an executable" % aia, file=sys.stderr)
        return 2
    files = [os.path.realpath(f) for f in argv[2:]] or default_files()
    commands, anchor_cache = {}, {}
    problems = 0
    checked_commands = checked_links = 0
    for path in files:
        name = os.path.relpath(path, ROOT)
        for number, kind, text in scan(path):
            if kind == "code":
                # A Markdown file named by a relative path in a code span
                # (docs/learning.md once named `../shared/docs/SPEC.md`,
                # outside the repository).
                if re.match(r"^(?:\.\./)+[\w.-][\w./-]*\.md$", text.strip()):
                    dest = os.path.normpath(
                        os.path.join(os.path.dirname(path), text.strip()))
                    if not (dest + os.sep).startswith(ROOT + os.sep):
                        print("%s:%d: path %s: outside the repository" %
                              (name, number, text.strip()))
                        problems += 1
                    elif not os.path.exists(dest):
                        print("%s:%d: path %s: no such file" %
                              (name, number, text.strip()))
                        problems += 1
                for m in COMMAND.finditer(text):
                    word = m.group(1)
                    checked_commands += 1
                    if not command_of(aia, word, commands):
                        print("%s:%d: `aia %s` is not a command of %s "
                              "(aia --help lists them)" % (name, number, word,
                                                           aia))
                        problems += 1
                continue
            for m in LINK.finditer(text):
                target = m.group(1)
                if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):
                    continue  # http:, https:, mailto:
                checked_links += 1
                file_part, _, fragment = target.partition("#")
                dest = (os.path.normpath(
                    os.path.join(os.path.dirname(path), file_part))
                        if file_part else path)
                if not (dest + os.sep).startswith(ROOT + os.sep):
                    print("%s:%d: link %s: outside the repository" %
                          (name, number, target))
                    problems += 1
                elif not os.path.exists(dest):
                    print("%s:%d: link %s: no such file" % (name, number,
                                                           target))
                    problems += 1
                elif (fragment and dest.endswith(".md") and
                      fragment not in anchors(dest, anchor_cache)):
                    print("%s:%d: link %s: %s has no heading #%s" %
                          (name, number, target, os.path.relpath(dest, ROOT),
                           fragment))
                    problems += 1
    if problems:
        print("%d problem(s) in the docs" % problems)
        return 1
    print("%d files: %d aia commands (%s) and %d links checked" %
          (len(files), checked_commands, ", ".join(sorted(commands)),
           checked_links))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
