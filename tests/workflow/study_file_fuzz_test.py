"""Property-based fuzzing of the study-file checker (workflow/study.py) with
hypothesis: arbitrary bytes and mutated study files are either read into
rows or refused with one StudyError line naming the file, never another
exception; valid studies read back to the rows they were written from.

  study_file_fuzz_test.py [examples]      each property on that many examples
                                           (default 300: ctest's run)
  study_file_fuzz_test.py --cpu-minutes M  a campaign: rounds of 1000 examples
                                           per property, fresh random seeds,
                                           until M CPU-minutes are used
"""

import os
import sys
import tempfile
import time

import hypothesis.configuration
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "workflow"))
import study  # noqa: E402

CAMPAIGN = len(sys.argv) > 2 and sys.argv[1] == "--cpu-minutes"
EXAMPLES = 1000 if CAMPAIGN else int(sys.argv[1]) if len(sys.argv) > 1 else 300
SETTINGS = settings(max_examples=EXAMPLES, deadline=2000, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
WORK = tempfile.mkdtemp(prefix="study_fuzz_")
hypothesis.configuration.set_hypothesis_home_dir(os.path.join(WORK, ".hypothesis"))
PATH = os.path.join(WORK, "study.tsv")

# Cells without the characters that structure the file.
cell = st.text(st.characters(blacklist_categories=("Cs", "Cc"), blacklist_characters="\t\r\n\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029#"),
               min_size=1, max_size=12).map(str.strip).filter(lambda s: s not in ("", "-") and '"' not in s)
value = st.one_of(st.integers(0, 10**6).map(str), st.sampled_from(["0.5", "arm:trunk", "trunk:right_arm@0,0,0,1,1,1"]))


@st.composite
def option_words(draw):
    words = []
    for name in draw(st.lists(st.sampled_from(sorted(study.DEFORM_OPTIONS)), max_size=4)):
        if not study.DEFORM_OPTIONS[name]:
            words.append(name)
        elif name == "--max-memory":
            words += [name, str(draw(st.integers(1, 10**6)))]
        else:
            words += [name, draw(value)]
    return words


@st.composite
def study_rows(draw):
    n = draw(st.integers(1, 5))
    outputs = draw(st.lists(cell, min_size=n, max_size=n, unique_by=os.path.normpath))
    rows = []
    for i in range(n):
        rows.append({"phantom": draw(cell), "grid": draw(cell), "organs": draw(st.one_of(st.just(""), cell)),
                     "pose": draw(cell), "options": draw(option_words()), "output": outputs[i],
                     "cores": draw(st.one_of(st.none(), st.integers(1, 64)))})
    return rows


def write_study(rows, path):
    resources = any(r["cores"] is not None for r in rows)
    header = study.REQUIRED + (["cores"] if resources else [])
    lines = ["# a study", "\t".join(header)]
    for r in rows:
        fields = [r["phantom"], r["grid"], r["organs"] or "-", r["pose"], " ".join(r["options"]) or "-", r["output"]]
        if resources:
            fields.append("" if r["cores"] is None else str(r["cores"]))
        lines.append("\t".join(fields))
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")


def check_refusal_or_rows(data):
    with open(PATH, "wb") as f:
        f.write(data)
    start = time.process_time()
    try:
        rows = study.read_study(PATH, check_files=False)
        assert rows, "read_study returned no rows without an error"
    except study.StudyError as e:
        message = str(e)
        assert message.startswith(PATH), message
        assert "\n" not in message, repr(message)
    assert time.process_time() - start < 1.0, f"{len(data)} bytes took {time.process_time() - start:.2f} CPU s"


@SETTINGS
@given(st.binary(max_size=4096))
def test_arbitrary_bytes(data):
    check_refusal_or_rows(data)


@SETTINGS
@given(study_rows(), st.data())
def test_mutated_study(rows, data):
    write_study(rows, PATH)
    raw = bytearray(open(PATH, "rb").read())
    for _ in range(data.draw(st.integers(1, 6))):
        kind = data.draw(st.sampled_from(["flip", "insert", "delete"]))
        at = data.draw(st.integers(0, max(len(raw) - 1, 0)))
        if kind == "flip" and raw:
            raw[at] = data.draw(st.sampled_from([9, 10, 13, 0, 34, 35, 45, 61, 0xff, 0xc3, ord("x")]))
        elif kind == "insert":
            raw[at:at] = data.draw(st.binary(min_size=1, max_size=8))
        elif raw:
            del raw[at:at + data.draw(st.integers(1, 8))]
    check_refusal_or_rows(bytes(raw))


@SETTINGS
@given(study_rows())
def test_valid_study_reads_back(rows):
    write_study(rows, PATH)
    read = study.read_study(PATH, check_files=False)
    assert len(read) == len(rows)
    for r, back in zip(rows, read):
        assert (back.phantom, back.grid, back.organs, back.pose, back.output) == \
            (r["phantom"], r["grid"], r["organs"], r["pose"], os.path.normpath(r["output"]))
        assert back.options == r["options"]
        assert back.resources == ({} if r["cores"] is None else {"cores": r["cores"]})
        assert back.line >= 3


if __name__ == "__main__":
    start, rounds = time.process_time(), 0
    budget = float(sys.argv[2]) * 60 if CAMPAIGN else 0
    while True:
        for test in (test_arbitrary_bytes, test_mutated_study, test_valid_study_reads_back):
            test()
        rounds += 1
        if time.process_time() - start >= budget:
            break
    print(f"study files: 3 properties x {rounds * EXAMPLES} examples, no finding ({time.process_time() - start:.1f} CPU s)")
