"""What the plotting and experiment tools share with aia's commands: bad
input is one line, `error: WHAT`, and exit code 2 (never a traceback); a
table is read with its file and line named in every problem; a figure is
written atomically (a Ctrl-C or a kill never leaves half a PNG under its
name) and Ctrl-C ends a tool with exit code 130 and no traceback.
"""

import csv
import errno
import math
import os
import sys


class BadInput(Exception):
    """A problem with a tool's input or arguments: `error: MESSAGE`, exit 2."""


# A path that cannot be read or written as given (bad input, exit 2); any
# other OSError (a full disk, an I/O error) is exit 1.
_PATH_ERRNOS = {errno.ENOENT, errno.ENOTDIR, errno.EISDIR, errno.EACCES,
                errno.EPERM, errno.EROFS, errno.ENAMETOOLONG, errno.ELOOP,
                errno.EEXIST}


def os_error(e):
    """An OSError as one error line and its exit code."""
    where = f"{e.filename}: " if e.filename else ""
    return (f"error: {where}{e.strerror or e}",
            2 if e.errno in _PATH_ERRNOS else 1)


def run(main):
    """Runs a tool's main() and exits with its code: 2 and one error line on
    BadInput or a path it cannot use (1 for other OSErrors: a full disk),
    130 on Ctrl-C, and 141 in silence when its output is a pipe whose reader
    has gone (`tool | head`), as a shell command ends."""
    try:
        code = main()
    except BadInput as e:
        print(f"error: {e}", file=sys.stderr)
        code = 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        code = 130
    except BrokenPipeError:
        # Python would report the failed flush of stdout at exit: point it
        # at /dev/null first.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        code = 141
    except OSError as e:
        line, code = os_error(e)
        print(line, file=sys.stderr)
    except ValueError as e:
        # The aia package's InputError (a ValueError): its one line.
        if type(e).__name__ != "InputError" or \
                not type(e).__module__.startswith("aia"):
            raise
        print(f"error: {e}", file=sys.stderr)
        code = 2
    sys.exit(code or 0)


def import_aia():
    """The aia package (build/python on the path, or installed), or one
    error line and exit 2 where it is not there."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    sys.path.insert(0, os.path.join(root, "build", "python"))
    try:
        import aia
    except ImportError as e:
        print(f"error: the aia package does not import ({e}): build it "
              "(tools/bootstrap.sh), or set PYTHONPATH=build/python "
              "(docs/python.md)", file=sys.stderr)
        sys.exit(2)
    return aia


def read_rows(path, columns, what):
    """The rows of the CSV file `path` (each a dict, its line under
    "_line"), which must have the `columns`; `what` names what it should be
    ("aia eval's summary.csv") in the messages."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            reader = csv.DictReader(f)
            rows = []
            for row in reader:
                if None in row:
                    raise BadInput(f"{path}:{reader.line_num}: more fields "
                                   "than the header has")
                row["_line"] = reader.line_num
                rows.append(row)
            header = reader.fieldnames or []
    except IsADirectoryError:
        raise BadInput(f"{path}: a folder, not {what}") from None
    except FileNotFoundError:
        raise BadInput(f"{path}: no such file") from None
    except UnicodeDecodeError:
        raise BadInput(f"{path}: not UTF-8 text, so not {what}") from None
    except (OSError, csv.Error) as e:
        raise BadInput(f"{path}: {e}") from None
    missing = [c for c in columns if c not in header]
    if missing:
        raise BadInput(f"{path}: no column {', '.join(missing)}: not {what}")
    return rows


def number(path, row, column, empty=None):
    """The finite number in `row[column]`; an empty field gives `empty`
    when that is not None (a field that may be blank), else it is refused."""
    text = (row.get(column) or "").strip()
    if text == "" and empty is not None:
        return empty
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise BadInput(f"{path}:{row['_line']}: {column}: must be a finite "
                       f"number, got {text!r}")
    return value


def check_output(path, inputs=()):
    """--out PATH: a file to write, not a folder and not one of the inputs."""
    if os.path.isdir(path):
        raise BadInput(f"--out: {path} is a folder; give the file to write")
    for i in inputs:
        if os.path.exists(path) and os.path.exists(i) and \
                os.path.samefile(path, i):
            raise BadInput(f"--out: {path} is an input; give another file")


class _NoPyplot:
    """pyplot where matplotlib is missing: the tool's --help and its checks
    work, and the first plot says what is missing in one line."""

    def __getattr__(self, name):
        raise BadInput(f"matplotlib is not installed for {sys.executable}: "
                       "Debian's python3-matplotlib (tools/bootstrap.sh "
                       "installs it); run the tool with /usr/bin/python3")


def pyplot():
    """matplotlib.pyplot on the headless backend, or a stand-in that raises
    BadInput when used where matplotlib is missing."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return _NoPyplot()
    return plt


def save_figure(fig, path, dpi, inputs=()):
    """Writes a matplotlib figure to `path` through a temporary file in its
    folder (made when missing), in the format of its extension (PNG without
    one), and closes it."""
    import matplotlib.pyplot as plt
    check_output(path, inputs)
    folder = os.path.dirname(os.path.abspath(path))
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as e:
        plt.close(fig)
        raise BadInput(f"--out: cannot make the folder {folder}: "
                       f"{e.strerror}") from None
    ext = os.path.splitext(path)[1].lstrip(".").lower() or "png"
    if ext not in fig.canvas.get_supported_filetypes():
        plt.close(fig)
        raise BadInput(f"--out: {path}: matplotlib writes no .{ext} files "
                       "(png, pdf, svg, ...)")
    tmp = os.path.join(folder, f".{os.path.basename(path)}.tmp.{os.getpid()}")
    try:
        fig.savefig(tmp, dpi=dpi, format=ext)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
    finally:
        plt.close(fig)
