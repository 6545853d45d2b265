"""Study files of voxmorph posture studies (workflow/Snakefile).

A study file is tab-separated text with a header line; lines starting with
'#' and blank lines are ignored. One row per (phantom, pose):

  phantom   name of the phantom (a summary column), e.g. AM
  grid      label grid file (any format `voxmorph deform` reads)
  organs    organ table (ID name tissue density), or empty / '-'
  pose      pose file (JSON, docs/POSES.md)
  options   further `voxmorph deform` options, or empty / '-':
            --preserve-volumes[=rest], --samples K, --max-memory MB, --dilation MM,
            --vertices N, --separate A:B[@box], --refine-iterations N,
            --max-tets N, --allow-growth, --cpu, --flag PCT
  output    the row's output folder (unique)

Optional columns set the row's job resources (defaults in the Snakefile's
config): cores, mem_mb, gpus, runtime (minutes).

Relative paths are relative to the directory snakemake runs in (--directory,
the repository root for `./run study`).
"""

import csv
import os
import hashlib
import re
import shlex
from dataclasses import dataclass, field

REQUIRED = ["phantom", "grid", "organs", "pose", "options", "output"]
RESOURCES = ["cores", "mem_mb", "gpus", "runtime"]

# deform options a row may give, and whether each takes a value. Outputs
# (-o, --report, --plots, --posed-*) belong to the workflow.
DEFORM_OPTIONS = {
    "--preserve-volumes": False,
    "--samples": True,
    "--max-memory": True,
    "--dilation": True,
    "--vertices": True,
    "--separate": True,
    "--refine-iterations": True,
    "--max-tets": True,
    "--allow-growth": False,
    "--max-body-change": True,
    "--max-bone-change": True,
    "--force": False,
    "--cpu": False,
    "--flag": True,
}


# deform options that shape the rest state `voxmorph prepare` saves (the
# cage options and the extra separations): rows of one phantom (grid and
# organ table) that give the same ones share one prepared state.
REST_OPTIONS = ("--dilation", "--vertices", "--separate")


class StudyError(Exception):
    """A fault of the study file: its message names the file and line."""


@dataclass
class Row:
    phantom: str
    grid: str
    organs: str  # "" without an organ table
    pose: str
    options: list
    output: str
    line: int
    resources: dict = field(default_factory=dict)

    @property
    def max_memory_mb(self):
        for i, o in enumerate(self.options):
            if o == "--max-memory":
                return int(self.options[i + 1])
            if o.startswith("--max-memory="):
                return int(o.split("=", 1)[1])
        return None


    @property
    def rest_options(self):
        """The row's options that shape the rest state, as `prepare` takes them."""
        out, i = [], 0
        while i < len(self.options):
            name, _, inline = self.options[i].partition("=")
            takes = DEFORM_OPTIONS.get(name, False)
            value = inline if inline or not takes else self.options[i + 1]
            if takes and not inline:
                i += 1
            if name in REST_OPTIONS:
                out += [name, value]
            i += 1
        return out

    @property
    def preparable(self):
        """Whether the row's deform takes a prepared state (in core only)."""
        return self.max_memory_mb is None


@dataclass
class PreparedGroup:
    name: str  # the prepared file's name, without .vxprep
    grid: str
    organs: str
    options: list  # rest_options of its rows
    poses: list  # its rows' poses, each once, in study order
    rows: list


def prepared_groups(rows):
    """The prepared states a study needs: one per phantom (grid, organ table)
    and rest options, holding the poses of its rows (those that run in
    core). Named by the phantom; where one phantom needs several, each name
    adds a digest of its grid, organ table and options."""
    groups = {}
    for r in rows:
        if not r.preparable:
            continue
        key = (r.phantom, os.path.abspath(r.grid), os.path.abspath(r.organs) if r.organs else "", tuple(r.rest_options))
        g = groups.setdefault(key, PreparedGroup("", r.grid, r.organs, r.rest_options, [], []))
        if r.pose not in g.poses:
            g.poses.append(r.pose)
        g.rows.append(r)
    per_phantom = {}
    for key in groups:
        per_phantom[key[0]] = per_phantom.get(key[0], 0) + 1
    for key, g in groups.items():
        base = re.sub(r"[^A-Za-z0-9_.-]", "_", key[0]) or "phantom"
        if per_phantom[key[0]] > 1:
            base += "_" + hashlib.sha256(repr(key[1:]).encode()).hexdigest()[:8]
        g.name = base
    return list(groups.values())


def _empty(text):
    return text is None or text.strip() in ("", "-")


def _parse_options(text, where):
    if _empty(text):
        return []
    try:
        words = shlex.split(text)
    except ValueError as e:
        raise StudyError(f"{where}: options: {e}")
    i = 0
    while i < len(words):
        name, _, inline = words[i].partition("=")
        if name not in DEFORM_OPTIONS:
            raise StudyError(f"{where}: option '{words[i]}' is not one a study row may give "
                             f"({', '.join(sorted(DEFORM_OPTIONS))})")
        if DEFORM_OPTIONS[name] and not inline:
            if i + 1 >= len(words):
                raise StudyError(f"{where}: option {name} needs a value")
            i += 1
        if name == "--max-memory":
            value = inline or words[i]
            if not value.isdigit():
                raise StudyError(f"{where}: --max-memory needs a whole number of MB, got '{value}'")
        i += 1
    return words


def read_study(path, check_files=True):
    """The rows of a study file; raises StudyError on the first fault."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            lines = [(n, l) for n, l in enumerate(f, 1) if l.strip() and not l.lstrip().startswith("#")]
    except OSError as e:
        raise StudyError(f"{path}: cannot read: {e.strerror}")
    except UnicodeDecodeError as e:
        raise StudyError(f"{path}: not UTF-8 text (byte {e.start} of the file)")
    for n, l in lines:
        if "\0" in l:
            raise StudyError(f"{path}:{n}: a NUL character (not a text file)")
    if not lines:
        raise StudyError(f"{path}: no header line")
    reader = csv.reader([l for _, l in lines], delimiter="\t", quoting=csv.QUOTE_NONE)
    records = list(reader)
    header = [h.strip() for h in records[0]]
    missing = [c for c in REQUIRED if c not in header]
    if missing:
        raise StudyError(f"{path}:{lines[0][0]}: header lacks column(s) {', '.join(missing)} "
                         f"(tab-separated: {' '.join(REQUIRED)})")
    unknown = [c for c in header if c not in REQUIRED + RESOURCES]
    if unknown:
        raise StudyError(f"{path}:{lines[0][0]}: unknown column(s) {', '.join(unknown)}")
    rows, outputs = [], {}
    for (line, _), record in zip(lines[1:], records[1:]):
        where = f"{path}:{line}"
        if len(record) != len(header):
            raise StudyError(f"{where}: {len(record)} tab-separated fields, the header has {len(header)}")
        cell = {h: v.strip() for h, v in zip(header, record)}
        for c in ("phantom", "grid", "pose", "output"):
            if _empty(cell[c]):
                raise StudyError(f"{where}: empty {c}")
        output = os.path.normpath(cell["output"])
        if output in outputs:
            raise StudyError(f"{where}: output folder {output} is also line {outputs[output]}'s")
        outputs[output] = line
        organs = "" if _empty(cell["organs"]) else cell["organs"]
        if check_files:
            for c, p in (("grid", cell["grid"]), ("pose", cell["pose"]), ("organs", organs)):
                if p and not os.path.isfile(p):
                    raise StudyError(f"{where}: {c} file {p} not found")
        resources = {}
        for c in RESOURCES:
            if c in cell and not _empty(cell[c]):
                if not cell[c].isdigit():
                    raise StudyError(f"{where}: {c} must be a whole number, got '{cell[c]}'")
                resources[c] = int(cell[c])
        rows.append(Row(cell["phantom"], cell["grid"], organs, cell["pose"], _parse_options(cell["options"], where),
                        output, line, resources))
    if not rows:
        raise StudyError(f"{path}: no rows under the header")
    return rows


def summary_folder(rows):
    """Default folder of the study's summary: the rows' common parent."""
    folders = [os.path.abspath(r.output) for r in rows]
    common = os.path.commonpath(folders) if len(rows) > 1 else os.path.dirname(folders[0])
    if common in folders:  # one row's folder holds the others
        common = os.path.dirname(common)
    return os.path.relpath(common)
