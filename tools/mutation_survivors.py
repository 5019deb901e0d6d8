"""Every mutant a full mutation run did not kill, with its diff and why it survives.

``python tools/mutation_survivors.py WORKDIR [--out FILE]`` reads a kept mutmut work
directory of ``python tools/mutation.py --keep --workdir WORKDIR`` (its ``tree/``) and
writes a Markdown table of the mutants in scope that were neither killed nor listed as
equivalent in ``tools/mutation_equivalents.toml``: name, the changed line (original and
mutant) and a class saying why no test fails on it. The classes are assigned by the
rules in :data:`RULES` (first match wins) from the changed line and the function; a
mutant no rule matches is listed as ``unexplained``, to be looked at by hand (a test, a
documented equivalent, or a new rule with its reason).

The diff is read from the mutated sources themselves (each mutant is a copy of its
function, ``x_NAME__mutmut_N``, beside ``x_NAME__mutmut_orig``), so no mutmut command
runs and nothing is changed.
"""

from __future__ import annotations

import argparse
import ast
import difflib
import fnmatch
import re
import sys
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from mutation import _statuses, load_equivalents  # noqa: E402


@dataclass(frozen=True)
class Rule:
    """A class of surviving mutants: a regular expression on ``-old ## +new`` (and on
    the mutant's function name, when given) and the reason such mutants survive."""

    name: str
    reason: str
    diff: str = ""
    function: str = ""
    whole: bool = False  # match ``diff`` on the whole diff, not on the changed part

    def matches(self, function: str, diff: str) -> bool:
        if self.function and not re.search(self.function, function):
            return False
        text = diff if self.whole else change_of(diff)
        return not self.diff or re.search(self.diff, text) is not None


def change_of(diff: str) -> str:
    """The part of a one-line change that differs, as ``context<old->new>`` (the 40
    characters before it, then the old and new text), so that a rule looks at what the
    mutation changed and not at the rest of the line; a longer diff is returned whole."""
    parts = diff.split(" ## ")
    if len(parts) != 2 or not (parts[0].startswith("-") and parts[1].startswith("+")):
        return diff
    a, b = parts[0][1:], parts[1][1:]
    p = 0
    while p < min(len(a), len(b)) and a[p] == b[p]:
        p += 1
    q = 0
    while q < min(len(a), len(b)) - p and a[len(a) - 1 - q] == b[len(b) - 1 - q]:
        q += 1
    before, after = a[max(0, p - 40) : p], a[len(a) - q :][:20]
    return f"{before}<{a[p : len(a) - q]}->{b[p : len(b) - q]}>{after}"


#: First match wins: the narrow classes first. ``diff`` patterns see the changed part of
#: the line as ``context<old->new>suffix`` (:func:`change_of`) unless ``whole``.
RULES: tuple[Rule, ...] = (
    Rule(
        "same operation spelled otherwise",
        "einsum subscripts in upper case (einsum takes either case), an axis of -1 "
        "written +1 on a two-dimensional array, or an argument dropped whose default is "
        "the value it had (reduceat's and concatenate's axis 0, argsort's and lfilter's "
        "last axis): the same operation",
        diff=r'einsum\("[^"<]*<[a-z.,>-]+->[A-Z.,>-]+>|axis=<-->\+>|'
        r"(reduceat|argsort|lfilter|concatenate|stack)\(.*<,? ?axis=(0|-1)->>",
    ),
    Rule(
        "dtype, shape or strictness argument",
        "a dtype, reshape or zip-strictness argument changed or dropped: every caller "
        "already passes arrays of that dtype and shape (numpy reads any negative size in "
        "reshape as 'the rest'), so nothing changes for the inputs the code accepts",
        diff=r"(dtype=|strict=|astype\()<|<[^>]*(dtype=|strict=)[^>]*->|"
        r"reshape\([^<]{0,40}<-?1?->|reshape\(<-1->|reshape\(<[^>]*->None>|"
        r"asarray\([^<]*<, dtype=[a-z]+->",
    ),
    Rule(
        "tie or tolerance edge",
        "a comparison turned strict or non-strict, or a tolerance moved (by a rounding, "
        "a sign or a factor): it decides only cases at or within round-off of a "
        "boundary, and the inputs the code meets sit either exactly on it (where either "
        "answer is as right as the other) or far from it, so the size of a small "
        "tolerance is not observable",
        diff=r"[<>]<=->>|[<>]<->=>|(1e-\d+|MERGE|DT_QUANTUM|1e3)[^<]{0,8}<|"
        r"<[^>]*(1e-\d+|1e3|1e12)[^>]*->|->[^>]*(1\.0+\d*e-\d+|1001\.0|1000000000001\.0)|"
        r"<[+-]->[+-]> ?(1e-|\d+ \* DT_QUANTUM|1e3 \* MERGE|MERGE)|"
        r"<1[01]?->1[01]> \* DT_QUANTUM",
    ),
    Rule(
        "unread sentinel or diagnostic",
        "a fill value that marks entries never read (-1: 'not set'), or a diagnostic "
        "count of ConstantErrorResponse (nodes, periods) no caller computes with",
        diff=r"np\.full\((len\([^)]*\)|n), <|self\.nodes|counts\[|_count\(",
        whole=True,
    ),
    Rule(
        "text",
        "a string literal that is only an error message, a label or a report key "
        "changed: no computation reads it",
        diff=r"^(?!.*(==|!=| in \(|kind=|side=|vertical|sensor|which|mode)).*"
        r'"[^"<]*<[^>]*->[^>]*>[^"]*"',
    ),
    Rule(
        "work partition or cache",
        "a block size, chunk, thread count, cache key or cache entry changed: the work "
        "is cut or reused differently and the numbers stay the same by construction "
        "(tests assert identical results across thread counts, blocks and cache reuse; "
        "a transition missing from a cache is computed on demand)",
        diff=r"(1024|1025|4096|4097|1 << 1[23]|CHUNK|SPLIT|_memo|_CACHE|_bounded_put|"
        r"cached = |\.get\(|threads|max_workers|cpu_count|ThreadpoolController|"
        r"limits|_BLAS|per_block|_blocks\()",
        whole=True,
    ),
    Rule(
        "work partition or cache",
        "thread and BLAS control: the same numbers on any number of threads (tested)",
        function=r"engine_threads|single_thread_blas|run_blocks|_blocks$|_chunks",
    ),
    Rule(
        "faster path declined",
        "in the choice of a faster path (periodic lifting, the phase template, a "
        "uniform output grid, closed-form windows, structured transitions) or its "
        "bookkeeping: the change makes the general path run, or builds a path's table "
        "for more or other entries than it uses; the results agree with the general path "
        "to round-off (the tests compare the paths, and assert that the main ones are "
        "taken)",
        function=r"make_windows|_cacheable|phase_step|fine_aligned|_lifting|_tile|"
        r"_lifted_fine|_OffsetTable|prepare_fine|_cached_offset_table|_cached_nav_table|"
        r"_cached_integrals|_rotation_integrals|_nav_on_grid|_partial_on_grid|"
        r"_fine_on_grid|_in_window|fine_nav|fine_states|_use_structured|_structured|"
        r"_transitions?$|_grid_step|_restrict|_recurs|period",
    ),
    Rule(
        "work partition or cache",
        "where the scan restarts a block (so that e^{-lambda t} stays in floating-point "
        "range) or whether _group_sum sorts first: every choice gives the same states "
        "and sums (equal keys summed in another order differ by round-off only); the "
        "tests compare the scan with the plain recurrence across many blocks and "
        "_group_sum with sums by hand",
        function=r"^x_scan$|^x__group_sum$",
    ),
    Rule(
        "value already in range",
        "a clip, a parity or a spare row of the Chebyshev integration: its nodes are "
        "already in [-1, 1], (-1)^(k+1) = (-1)^(k-1), and the extra row is never read",
        function=r"integral_of_series",
    ),
    Rule(
        "unread model part",
        "the navigation model that places the initial errors: only its nine navigation "
        "states are read (the initial errors are navigation states, so the attitude and "
        "the error blocks it might carry do not enter)",
        function=r"^x_source_set$",
        diff=r"nav_model|unit_column|np\.full\(n",
        whole=True,
    ),
    Rule(
        "faster path declined",
        "how the lifted coarse states count the periods (a period left to the last, "
        "partial, branch is computed there the same way) or the grid step read from a "
        "grid that starts at 0: the same states",
        function=r"_lifted_coarse",
        diff=r"whole =|n_per =|h = float",
        whole=True,
    ),
    Rule(
        "tie or tolerance edge",
        "the worst-case walk's start vertex for a source with x exactly 0, or its crossing "
        "angle offset by pi (the angles are taken mod pi: the same order): only exact "
        "ties move",
        function=r"^x__walk$",
        diff=r"s0 = |theta",
        whole=True,
    ),
    Rule(
        "unread sentinel or diagnostic",
        "a value computed but not read: signs returned where only the norm is asked for, "
        "the fields of ConstantErrorResponse and _Run that no caller reads (its time grids, "
        "its SourceSet), phi1's and the rotation axis's placeholder at zero (replaced or "
        "multiplied by a zero angle), a lookup's default index (-1 or -2, never used)",
        function=r"worst_case_norm|pattern_maximum|_constant_error_response|"
        r"xǁ_Runǁ__init__|phi1|TimelineHistoryǁevaluate|_source_inputs|signed_coefficients",
        diff=r"or True|None, fine|t_coarse, coarse|None, coarse|self\.sources|"
        r"1\.0, z|rate, (1|2)\.0|default=|-1, 9|-2, 9",
        whole=True,
    ),
    Rule(
        "faster path declined",
        "the constant-response set-up: the phase step or the fine-output tables not "
        "prepared ahead (they are then made when first needed, or the general path "
        "runs), a two-point coarse grid taken by the general scan, or a timeline's "
        "pieces not marked constant (the general windows then integrate them): the same "
        "numbers",
        function=r"_constant_error_response|TimelineHistoryǁpieces",
    ),
    Rule(
        "work partition or cache",
        "the key under which a static (zero-rate) transition is cached, or the rate "
        "used to pick the sub-step: another cache slot or a safer step, same transitions",
        function=r"DiscretizerǁDiscretizerǁkey|Discretizerǁkey|Discretizerǁ__init__",
    ),
    Rule(
        "tie or tolerance edge",
        "the step engine's merge distance of 10 time quanta made 11: nodes closer than "
        "that are one node either way",
        function=r"make_steps",
        diff=r"1<0->1> \* DT_QUANTUM",
    ),
    Rule(
        "same operation spelled otherwise",
        "the Gauss-Markov covariance's scans start from a zero state (their start time is "
        "then irrelevant), a covariance already symmetric symmetrized again, "
        "reduceat's default axis, the window's coarse index it never reads",
        function=r"x__gauss_markov$|white_noise_covariance",
        diff=r"scan\(mu, 1\.0|scan\(nu\.ravel\(\), 1\.0|swapaxes\([a-z]+, 2, 2\)|"
        r"nd\.first, \)|win\.phase, None|3:7\]",
        whole=True,
    ),
    Rule(
        "quadrature resolution",
        "the Gauss-Markov covariance's node count or phase budget (8 -> 9 nodes, a "
        "budget from 3 instead of 2 times the fastest mode): converged either way",
        function=r"x__gauss_markov$",
        diff=r"np\.maximum\(win\.n, 9\)|3\.0 \* float",
        whole=True,
    ),
    Rule(
        "unread model part",
        "a source's value set (=) instead of added (+=) into its matrix entry: the same "
        "unless two sources share an entry, which constant_sources never makes; the "
        "error blocks a layout carries, unused by the fast engine (it treats IMU errors "
        "as inputs); the default of the vertical mode, which every caller passes",
        function=r"SourceSetǁsigned|layout_for|constant_sources",
        diff=r"\+= v|bias|vertical: str",
        whole=True,
    ),
    Rule(
        "dtype, shape or strictness argument",
        "vehicle_to_imu's squeeze flag and result dtype: its callers pass 3-D stacks of one dtype",
        function=r"vehicle_to_imu",
        diff=r"squeeze|result_type",
        whole=True,
    ),
    Rule(
        "same operation spelled otherwise",
        "the diagonal scaling of the navigation block before its eigen-decomposition "
        "(a similarity for conditioning: any positive scale gives the same modes once "
        "undone), and the real eigenvalues' imaginary round-off kept or not",
        function=r"NavModesǁ__post_init__",
        diff=r"scale_all|lam\.real|np\.where\(None",
        whole=True,
    ),
    Rule(
        "tie or tolerance edge",
        "an interval looked up at a node time from the other side (searchsorted's side "
        "dropped): the attitude is continuous there, so either interval gives it",
        diff=r'<, side="right"->>|side="right"\) - 1, <0->None>|<0->None>, len|'
        r"len\(self\.omega_n\) <-->\+>|len\(self\.omega_n\) - <1->2>",
        function=r"attitude_at|interval_index|ScheduleHistoryǁ__init__",
    ),
    Rule(
        "same operation spelled otherwise",
        "the white-noise closed form zeroes the vertical-velocity input row of a clamped "
        "model, but the clamped model's modes leave dv_U out altogether (NavModes keeps "
        "states 0-4, 6, 7), so that row never reaches a mode: the zeroing is redundant "
        "(checked by applying the mutant by hand), and the clamped channel's variances "
        "are tested to stay exactly 0",
        function=r"white_noise_covariance",
        diff=r"clamped|g\[5, :\]|g\[6, :\]",
        whole=True,
    ),
    Rule(
        "same operation spelled otherwise",
        "the lifted coarse states' geometric sum: the inner guard only keeps a division "
        "finite where the outer choice discards its result (modes with e^{lambda P} = 1), "
        "and k - 0j is k + 0j",
        function=r"_lifted_coarse",
        diff=r"np\.where\(den == 0, k|num / np\.where",
        whole=True,
    ),
    Rule(
        "search heuristic",
        "inside the heuristic searches of a sign pattern (starting points, walk order, "
        "exhaustive block sizes, descent steps): the result moves but stays within the "
        "documented guarantees (a bound no pattern goes below, a value some pattern "
        "attains, within the largest source of the target), which is what the tests "
        "check against brute force",
        function=r"closest_pattern|_closest_exhaustive|_descend|sign_pattern_range|"
        r"figure_reach|_lower_bound|_starts",
    ),
    Rule(
        "quadrature resolution",
        "the number of quadrature nodes or the phase budget of a window changed: the "
        "Chebyshev quadrature is converged with room to spare (halving the budget "
        "changes nothing beyond round-off, tested), so more or fewer nodes give the "
        "same numbers to the tests' tolerances",
        function=r"points_for|chebyshev|fejer|_nodes|_direct_g",
    ),
    Rule(
        "sign of a zero-mean noise or of a covariance factor",
        "the sign of a noise input or of a Gauss-Markov drive changed: covariances "
        "(K Q K^T) and the law of a zero-mean Gaussian process are the same for x "
        "and -x",
        function=r"white_noise_covariance|_gauss_markov|gauss_markov_covariance|simulate",
        diff=r"<\+?=?->-?=?>|<-->\+?>|<\+->-?>",
    ),
)


def _functions(path: Path) -> dict[str, list[str]]:
    """Source lines of every ``*__mutmut_*`` function of a mutated module."""
    src = path.read_text()
    lines = src.splitlines()
    out = {}
    for node in ast.walk(ast.parse(src)):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and "__mutmut_" in node.name:
            out[node.name] = [line.strip() for line in lines[node.lineno : node.end_lineno]]
    return out


def diff_of(tree: Path, name: str, cache: dict) -> str:
    """``-old ## +new`` lines of mutant ``name`` against its original function."""
    module, func = name.rsplit(".", 1)
    path = tree / "mutants" / (module.replace(".", "/") + ".py")
    if path not in cache:
        cache[path] = _functions(path)
    funcs = cache[path]
    orig = re.sub(r"__mutmut_\d+$", "__mutmut_orig", func)
    if func not in funcs or orig not in funcs:
        return "?"
    lines = difflib.unified_diff(funcs[orig], funcs[func], lineterm="", n=0)
    return " ## ".join(
        line for line in lines if line[:1] in "+-" and not line.startswith(("---", "+++"))
    )


def classify(name: str, diff: str) -> Rule | None:
    function = re.sub(r"__mutmut_\d+$", "", name.rsplit(".", 1)[1])
    return next((r for r in RULES if r.matches(function, diff)), None)


def survivors(tree: Path) -> list[tuple[str, str]]:
    """``(name, mutmut's status)`` of the mutants in scope that were not killed and are not
    documented as equivalent (the harness's rule, from the same statuses)."""
    equivalents = load_equivalents()
    out = []
    for name, status in sorted(_statuses(tree).items()):
        if status in ("killed", "timeout"):
            continue
        if any(name == k or fnmatch.fnmatch(name, k) for k in equivalents):
            continue
        out.append((name, status))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("workdir", type=Path, help="kept work directory of tools/mutation.py")
    ap.add_argument("--out", type=Path, help="write the Markdown here (default: stdout)")
    args = ap.parse_args(argv)
    tree = args.workdir / "tree"
    cache: dict = {}
    rows = []
    for name, status in survivors(tree):
        if status == "not checked":
            rows.append(("not checked (run interrupted)", name, ""))
            continue
        diff = diff_of(tree, name, cache)
        rule = classify(name, diff)
        rows.append((rule.name if rule else "unexplained", name, diff))
    counts = Counter(c for c, _, _ in rows)
    reasons = {r.name: r.reason for r in reversed(RULES)}
    out = [
        "# Mutants the full run did not kill",
        "",
        "Generated by `python tools/mutation_survivors.py WORKDIR` from a kept work "
        "directory of `python tools/mutation.py --keep --workdir WORKDIR`; the classes "
        "are assigned by the rules in `tools/mutation_survivors.py` (see "
        "`docs/testing.md`).",
        "",
        f"{len(rows)} mutants in scope neither killed nor documented as equivalent.",
        "",
        "| class | mutants | why they survive |",
        "|---|---|---|",
    ]
    for cls, n in counts.most_common():
        why = reasons.get(cls, "no rule matches: to be looked at (a test, or a reason)")
        out.append(f"| {cls} | {n} | {why} |")
    out += ["", "| class | mutant | change (original ## mutant) |", "|---|---|---|"]
    for cls, name, diff in sorted(rows):
        cell = diff.replace("|", "\\|")[:300]
        out.append(f"| {cls} | `{name}` | `{cell}` |")
    text = "\n".join(out) + "\n"
    if args.out:
        args.out.write_text(text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
