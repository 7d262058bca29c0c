"""What the scripts of bench/ share: the source root, running cellray (a
failure stops the script with the command and its stderr), the commit, and
writing a generated document atomically."""
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run_text(cmd):
    """stdout of cmd; exits with its status (after printing it and its stderr) when it fails."""
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.stderr.write(" ".join(cmd) + "\n" + p.stderr)
        raise SystemExit(p.returncode)
    return p.stdout


def run(cmd):
    """The JSON line that a cellray command prints last."""
    return json.loads(run_text(cmd).strip().splitlines()[-1])


def commit():
    return subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True).stdout.strip()


def write_doc(path, lines):
    """Writes lines to path through a temporary name (never a half-written document)."""
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(path + ".tmp", path)
    print(f"wrote {path}", file=sys.stderr)
