# SPDX-License-Identifier: GPL-3.0-or-later
"""Run every documented pointsurf command line against the shipped data (issue 27 item 8).

Usage: /usr/bin/python3 tests/docs/run_doc_examples.py --cli build/pointsurf [--root .] [--all]
       [--timeout 300] [--list] [--keep]

What is collected:
  * README.md and docs/*.md: the lines of ```bash, ```sh, ```console and plain ``` blocks that
    start with `pointsurf ` (or `./build/pointsurf `, `build/pointsurf `; a leading `$ ` is
    dropped); backslash-continued lines are joined. Everything else in a block is left alone:
    `./pointsurf.sh ...` set-up lines (they install Debian packages and build: not something a
    test should do), pip and python lines, other tools. Python blocks are run by
    python/tests/test_docs.py. Synopsis lines (`pointsurf crop IN OUT [options]`: an upper-case
    placeholder word or a `[`) and printed output (`pointsurf run: error: ...`) are not commands.
  * `pointsurf --help` and `pointsurf COMMAND --help` for every command that --help lists: the
    lines under "Example:" / "Examples:".

How they run: the commands of one source (one .md file, one --help page) run in order in one
scratch directory, so a later line may use what an earlier line wrote (as a reader copying the
block would). The scratch directory holds symlinks `data` and `examples` into the repository and
an empty `out/`; every output lands in it. The binary given by --cli replaces `pointsurf`; `--threads 2` is
added to each call that does not set threads and whose command accepts it. A command fails when
it exits non-zero, runs past --timeout, or names an input (its first file argument, --reference,
--file) that neither the repository ships nor an earlier line of its source wrote.

Commands meant to fail: end the line in the doc with a comment `# fails: WHY`; it must then exit
non-zero (1, 2 or 3), and exiting 0 is the failure. Commands that cannot run are listed in
PLACEHOLDERS below with the reason; heavy ones in SLOW (run only with --all). docs/stages.md's
examples are the --help examples (StagesDoc.CommittedFileIsTheRegistrys keeps the file equal to
`pointsurf stages --markdown`), so they run once, from --help, unless --all.
"""
import argparse
import os
import re
import shlex
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# (source, start of the command) -> why it cannot run here. Keep this short: prefer fixing the doc.
PLACEHOLDERS = {
    ("docs/segment.md", "pointsurf render b9_picture.ply"):
        "b9_picture.ply is made by bench/segment/b9_outline_picture.py (a Python step of the figure recipe)",
}

# (source, start of the command) -> why it is left to --all.
SLOW = {
}

FILE_EXTENSIONS = (".ply", ".xyz", ".pts", ".txt", ".csv", ".pcd", ".las", ".laz", ".e57", ".off",
                   ".obj", ".stl", ".json", ".geojson", ".png", ".html")
LINKS = ("data", "examples")  # what the scratch directory links to in the repository
COMMAND_START = re.compile(r"^(\./build/|build/)?pointsurf\s")
SYNOPSIS_WORD = re.compile(r"^\[|^[A-Z][A-Z0-9_]+(\.[a-z]+)?\]?$")


def strip_comment(line):
    """The line without a trailing `# ...` comment (outside quotes); also returns the comment."""
    quote = None
    for i, c in enumerate(line):
        if quote:
            if c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c == "#" and (i == 0 or line[i - 1].isspace()):
            return line[:i].rstrip(), line[i + 1:].strip()
    return line.rstrip(), ""


def doc_commands(path):
    """(line number, command, comment) of every pointsurf call in a markdown file's shell blocks."""
    found = []
    fence = None
    pending = None
    for number, raw in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        text = raw.strip()
        if text.startswith("```"):
            fence = None if fence is not None else text[3:].strip()
            pending = None
            continue
        if fence not in ("bash", "sh", "console", ""):
            continue
        if pending is None:
            if text.startswith("$ "):
                text = text[2:].lstrip()
            if not COMMAND_START.match(text):
                continue
            pending = [number, text]
        else:
            pending[1] += " " + text
        if pending[1].endswith("\\"):
            pending[1] = pending[1][:-1].rstrip()
            continue
        command, comment = strip_comment(pending[1])
        found.append((pending[0], command, comment))
        pending = None
    return found


def help_text(cli, *args):
    return subprocess.run([cli, *args, "--help"], capture_output=True, text=True, timeout=60).stdout


def help_examples(text):
    lines, inside = [], False
    for line in text.splitlines():
        if re.match(r"^Examples?:\s*$", line):
            inside = True
            continue
        if inside:
            if not line.startswith("  "):
                inside = False
                continue
            command, comment = strip_comment(line.strip())
            if COMMAND_START.match(command):
                lines.append((0, command, comment))
    return lines


def listed_commands(text):
    names, inside = [], False
    for line in text.splitlines():
        if line.startswith("Commands:"):
            inside = True
        elif inside and re.match(r"^  [a-z]", line):
            names.append(line.split()[0])
        elif inside and not line.strip():
            break
    return names


def segments(command):
    """The command split at `&&` into (shell text, tokens) pairs."""
    parts = []
    for part in command.split("&&"):
        part = part.strip()
        parts.append((part, shlex.split(part)))
    return parts


def is_synopsis(tokens):
    return any(SYNOPSIS_WORD.match(t) for t in tokens[1:])


def is_output(tokens):
    return len(tokens) > 1 and tokens[1].endswith(":")


def needed_inputs(tokens):
    """Files a call reads: the first file-like positional, and the values of --reference / --file."""
    needed = []
    args = tokens[2:]
    for i, t in enumerate(args):
        if t in ("--reference", "--file") and i + 1 < len(args):
            needed.append(args[i + 1])
    positional = [t for i, t in enumerate(args)
                  if not t.startswith("-") and (i == 0 or not args[i - 1].startswith("--"))
                  and t not in (">", "2>") and t.lower().endswith(FILE_EXTENSIONS)]
    if positional and tokens[1] not in ("stages",):
        needed.append(positional[0])
        if tokens[1] in ("register", "merge", "register-many", "report"):
            needed.extend(positional[1:-1] if tokens[1] != "register" else positional[1:2])
    return needed


def shell_line(part, tokens, cli, threaded):
    """The doc's text with the binary substituted and --threads 2 added where it is accepted."""
    text = re.sub(r"^(\./build/|build/)?pointsurf(?=\s)", shlex.quote(cli), part)
    if tokens[1] in threaded and not any(t.startswith("--threads") for t in tokens):
        redirect = re.search(r"\s\d?>", text)
        cut = redirect.start() if redirect else len(text)
        text = text[:cut] + " --threads 2" + text[cut:]
    return text


def prepare(scratch, tokens):
    for t in tokens:
        if "/" in t and not t.startswith(("/", "-")) and t.split("/")[0] not in LINKS:
            (scratch / t).parent.mkdir(parents=True, exist_ok=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cli", required=True, help="the pointsurf binary")
    parser.add_argument("--root", default=str(Path(__file__).resolve().parents[2]), help="the repository")
    parser.add_argument("--all", action="store_true", help="also run the SLOW commands")
    parser.add_argument("--timeout", type=float, default=300, help="seconds per command")
    parser.add_argument("--list", action="store_true", help="only list what would run")
    parser.add_argument("--keep", action="store_true", help="keep the scratch directories")
    args = parser.parse_args()
    root = Path(args.root).resolve()
    cli = str(Path(args.cli).resolve())

    sources = []  # (name, [(line, command, comment)])
    top = help_text(cli)
    sources.append(("pointsurf --help", help_examples(top)))
    threaded = set()
    for name in listed_commands(top):
        text = help_text(cli, name)
        if "--threads" in text:
            threaded.add(name)
        sources.append((f"pointsurf {name} --help", help_examples(text)))
    from_help = {command for _, commands in sources for _, command, _ in commands}
    for md in [root / "README.md", *sorted((root / "docs").glob("*.md"))]:
        sources.append((str(md.relative_to(root)), doc_commands(md)))

    counts = {"found": 0, "ran": 0, "passed": 0, "expected-fail": 0, "placeholder": 0, "slow": 0,
              "synopsis": 0, "output": 0, "same": 0}
    failures = []
    started = time.monotonic()
    for source, commands in sources:
        if not commands:
            continue
        scratch = Path(tempfile.mkdtemp(prefix="pointsurf-doc-"))
        for link in LINKS:
            os.symlink(root / link, scratch / link)
        (scratch / "out").mkdir()
        for number, command, comment in commands:
            place = f"{source}:{number}" if number else source
            parts = segments(command)
            if is_output(parts[0][1]):
                counts["output"] += 1
                continue
            if is_synopsis(parts[0][1]):
                counts["synopsis"] += 1
                continue
            counts["found"] += 1
            if source == "docs/stages.md" and command in from_help and not args.all:
                counts["same"] += 1
                continue
            key = next((k for k in PLACEHOLDERS if k[0] == source and command.startswith(k[1])), None)
            if key:
                counts["placeholder"] += 1
                print(f"  skip  {place}: {command}\n        placeholder: {PLACEHOLDERS[key]}")
                continue
            key = next((k for k in SLOW if k[0] == source and command.startswith(k[1])), None)
            if key and not args.all:
                counts["slow"] += 1
                print(f"  slow  {place}: {command}\n        left to --all: {SLOW[key]}")
                continue
            expect_fail = comment.startswith("fails:")
            if args.list:
                print(f"  list  {place}: {command}{'   (expected to fail)' if expect_fail else ''}")
                continue
            for part, tokens in parts:
                prepare(scratch, tokens)
            first_tokens = parts[0][1]
            missing = [] if expect_fail else [f for f in needed_inputs(first_tokens) if not (scratch / f).exists()]
            if missing:
                failures.append(f"{place}: {command}\n      names files not shipped nor written before: {', '.join(missing)}")
                print(f"  FAIL  {place}: {command}\n        missing input: {', '.join(missing)}")
                continue
            line = " && ".join(shell_line(p, t, cli, threaded) for p, t in parts)
            counts["ran"] += 1
            t0 = time.monotonic()
            proc = subprocess.Popen(["bash", "-c", line], cwd=scratch, stdout=subprocess.PIPE,
                                    stderr=subprocess.STDOUT, text=True, start_new_session=True)
            try:
                output, _ = proc.communicate(timeout=args.timeout)
                code = proc.returncode
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                output, _ = proc.communicate()
                code = None
            seconds = time.monotonic() - t0
            if code is None:
                verdict, why = "FAIL", f"timed out after {args.timeout:g} s"
            elif expect_fail:
                verdict, why = ("ok", "") if code in (1, 2, 3) else ("FAIL", f"meant to fail ({comment}) but exited {code}")
            else:
                verdict, why = ("ok", "") if code == 0 else ("FAIL", f"exit {code}")
            print(f"  {verdict:4}  exit {code if code is not None else '-'}  {seconds:6.2f} s  {place}: {command}")
            if verdict == "ok":
                counts["expected-fail" if expect_fail else "passed"] += 1
            else:
                tail = "\n".join("        | " + l for l in output.strip().splitlines()[-6:])
                print(tail)
                failures.append(f"{place}: {command}\n      {why}")
        if not args.keep:
            subprocess.run(["rm", "-rf", str(scratch)], check=False)
        else:
            print(f"  (kept {scratch}: {source})")

    total = time.monotonic() - started
    print(f"\n{counts['found']} documented commands: {counts['ran']} ran ({counts['passed']} passed, "
          f"{counts['expected-fail']} failed as documented), {counts['placeholder']} placeholders, "
          f"{counts['slow']} slow (--all), {counts['same']} in docs/stages.md the same as --help (--all runs them); not commands: {counts['synopsis']} synopsis lines, "
          f"{counts['output']} output lines; {total:.1f} s")
    if failures:
        print(f"\n{len(failures)} failed:")
        for f in failures:
            print("  " + f)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
