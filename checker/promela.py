"""A system as a Promela model for SPIN, generated from the compiled checker core.

Pipeline position: :mod:`checker.model` -> :mod:`checker.core` -> **checker.promela** ->
``model.pml`` -> :mod:`checker.spin` (compile ``pan``, run it, read its trails).

The Promela model is the transition system :func:`checker.search.explore` explores, over
the same states:

* The scan of one axis block is a pure function of the block (its axis part and tag
  parts, :mod:`checker.core`), the scan mode (normal, coarse update, prescan) and the
  block's own input.  The blocks of one table class (an axis, or a group of
  interchangeable axes) are numbered, and the closure of a class's initial blocks under
  every clock phase and input is computed here with the core's pieces: per block and
  mode the block under no input, the blocks of the inputs that change something, the
  block after a prescan pass, and the properties each step violates or reaches.  The
  tables grow with the blocks of one axis, not with the product of the axes.
* The tables are C arrays in a ``c_decl``; the state vector is Promela variables (the
  clock ``phase``, one block number per axis, and read-outs of the axis states and tag
  error codes that are functions of the block, so they add no states); one ``do`` loop
  offers one option per input (an input of one axis, nothing, a prescan pass), each a
  ``d_step`` that applies the scan rules of :meth:`CompiledModel.successors`: the chosen
  axis takes its input, every other axis scans with none, the clock advances, blocks of
  interchangeable axes are sorted (the same symmetry reduction as the Python search:
  the number of orbits does not depend on the order used to pick their
  representatives).
* Invariants and response bounds are ``assert`` statements, reachability goals are
  asserts that fail when the goal is reached (the trail is the witness), a
  ``deadlock_free`` property an assert on the successor; each property is reported once
  per run.  The initial state is the first configuration's; an option that is offered
  only there starts another configuration, so SPIN stores exactly the states of the
  Python search.

Output is deterministic: the same system and properties give the same text.

Example::

    >>> from statecharts.loader import load_spec
    >>> from checker.system import load_system, bundled_systems
    >>> from checker.model import Model
    >>> spec = load_spec()
    >>> pm = build(Model(spec, load_system(bundled_systems()["noncip"], spec)))
    >>> pm.text.count("active proctype scan()")
    1
"""

from __future__ import annotations

import re
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from checker.core import COARSE, NORMAL, PRESCAN, CompiledModel
from checker.model import Model
from checker.properties import Property

#: the generator's format; a model file names it in its first line
FORMAT = "motionchart-promela/1"
#: most properties a model can carry (one bit each in a 64-bit mask)
MAX_PROPERTIES = 64
#: most blocks of one table class (a block number is a Promela ``int``)
MAX_BLOCKS = 2**31 - 1


class ExportError(ValueError):
    """The system cannot be written as a Promela model (said why)."""


@dataclass
class TableClass:
    """The blocks of one axis, or of a group of interchangeable axes, and their steps."""

    leader: int
    axes: list[int]
    blocks: list[tuple[int, ...]] = field(default_factory=list)
    index: dict[tuple[int, ...], int] = field(default_factory=dict)
    #: (mode, block) -> (block, violated mask, reached mask), mode NORMAL or COARSE
    base: dict[tuple[int, int], tuple[int, int, int]] = field(default_factory=dict)
    #: (mode, block) -> [(local input, block, violated mask, reached mask)]
    moves: dict[tuple[int, int], list[tuple[int, int, int, int]]] = field(default_factory=dict)
    #: block -> (block after a prescan pass, violated, reached)
    prescan: dict[int, tuple[int, int, int]] = field(default_factory=dict)
    busy: list[bool] = field(default_factory=list)

    def number(self, block: tuple[int, ...]) -> tuple[int, bool]:
        i = self.index.get(block)
        if i is not None:
            return i, False
        if len(self.blocks) >= MAX_BLOCKS:
            raise ExportError(f"more than {MAX_BLOCKS:,} blocks of axis {self.leader}")
        i = len(self.blocks)
        self.index[block] = i
        self.blocks.append(block)
        return i, True


@dataclass
class PromelaModel:
    """A generated model and what is needed to read SPIN's results back."""

    text: str
    model: Model
    core: CompiledModel
    classes: list[TableClass]
    class_of: list[int]
    #: per axis: the global choice index of each local input number
    alphabet: list[list[int]]
    #: properties with an assert, in mask-bit order
    properties: list[Property]
    #: initial block vector per distinct initial state, and the assignment index it came from
    initials: list[tuple[tuple[int, ...], int]]
    names: list[str]
    seconds: float = 0.0
    #: whether the tables go to a C file of their own (large models: SPIN copies the
    #: model's text, and the C compiler parses a table file faster at -O0)
    side_tables: bool = False
    #: the text of that C file (None: the tables are in the model)
    tables: str | None = None

    @property
    def blocks(self) -> int:
        return sum(len(c.blocks) for c in self.classes)

    def core_state(self, phase: int, blocks: Sequence[int]) -> tuple[int, ...]:
        """The core's (canonical) state of a SPIN state."""
        vec = [phase]
        for ai, b in enumerate(blocks):
            vec.extend(self.classes[self.class_of[ai]].blocks[b])
        return self.core.canonical(vec)

    def dead(self, phase: int, blocks: Sequence[int]) -> bool:
        """Whether every successor of a SPIN state is the state itself (a deadlock)."""
        if self.core.spu != 1:
            return False  # the clock moves on every scan
        mode = COARSE if phase % self.core.spu == 0 else NORMAL
        prescan = self.core.has_prescan and not any(
            self.classes[self.class_of[ai]].busy[b] for ai, b in enumerate(blocks))
        for ai, b in enumerate(blocks):
            tc = self.classes[self.class_of[ai]]
            if tc.base[(mode, b)][0] != b or any(r[1] != b for r in tc.moves[(mode, b)]):
                return False
            if prescan and tc.prescan[b][0] != b:
                return False
        return True

    def step(self, phase: int, blocks: Sequence[int], axis: int, local: int, prescan: bool = False
             ) -> tuple[int, list[int], int, int]:
        """The successor of a SPIN state (as the generated model computes it): (phase,
        blocks, violated mask, reached mask); ``axis`` -1 is the nothing input."""
        spu = self.core.spu
        mode = COARSE if phase % spu == 0 else NORMAL
        out = list(blocks)
        bad = good = 0
        for ai, b in enumerate(blocks):
            tc = self.classes[self.class_of[ai]]
            if prescan:
                out[ai], x, y = tc.prescan[b]
            elif ai == axis:
                for c, b2, x, y in tc.moves[(mode, b)]:
                    if c == local:
                        out[ai] = b2
                        bad |= x
                        good |= y
                        break
                else:
                    raise KeyError(f"input {local} of axis {axis} is not offered")
                continue
            else:
                out[ai], x, y = tc.base[(mode, b)]
                if axis >= 0:
                    continue
            bad |= x
            good |= y
        return (phase + 1) % spu, out, bad, good


def _mask(props: Sequence[Property], bit: dict[str, int]) -> int:
    m = 0
    for p in props:
        k = bit.get(p.name)
        if k is not None:
            m |= 1 << k
    return m


def compute_tables(model: Model, *, progress: Callable[[int], None] | None = None) -> PromelaModel:
    """The table classes of ``model``: the closure of each class's initial blocks."""
    core = CompiledModel(model)
    if core.coupled:
        raise ExportError("a call reads a second axis (a bound master axis): the axes' tables are not "
                          "independent; check this system with `motionchart check`")
    asserted = [p for p in model.properties if p.kind in ("invariant", "response", "reachable", "deadlock_free")]
    if len(asserted) > MAX_PROPERTIES:
        raise ExportError(f"{len(asserted)} properties to assert; a model holds at most {MAX_PROPERTIES}")
    bit = {p.name: k for k, p in enumerate(asserted)}
    naxes = core.naxes
    # table classes: interchangeable axes share the leader's tables
    class_of = [-1] * naxes
    classes: list[TableClass] = []
    for group in core.symmetric_groups:
        lead = group[0]
        if any(core._leader[a] != lead for a in group):  # the core's own grouping
            raise ExportError("interchangeable axes with different inputs; export with symmetry off")
        for a in group:
            class_of[a] = len(classes)
        classes.append(TableClass(lead, list(group)))
    for ai in range(naxes):
        if class_of[ai] < 0:
            class_of[ai] = len(classes)
            classes.append(TableClass(ai, [ai]))
    alphabet = [core._alphabet(ai) for ai in range(naxes)]  # fixed order of an axis's inputs
    local_of = [{c: k for k, c in enumerate(alphabet[tc.leader])} for tc in classes]

    starts, lens = core.block_start, core.block_len
    initials: list[tuple[tuple[int, ...], int]] = []
    seen_initial: set[tuple[int, ...]] = set()
    spu = core.spu
    queues: list[deque[tuple[int, int]]] = [deque() for _ in classes]
    seen: list[set[tuple[int, int]]] = [set() for _ in classes]
    for a_index, (state, _bad, _good) in enumerate(core.initial_states()):
        vec: list[int] = []
        for ai in range(naxes):
            tc = classes[class_of[ai]]
            b, _new = tc.number(tuple(state[starts[ai]:starts[ai] + lens[ai]]))
            vec.append(b)
            if (state[0], b) not in seen[class_of[ai]]:
                seen[class_of[ai]].add((state[0], b))
                queues[class_of[ai]].append((state[0], b))
        for group in core.symmetric_groups:  # SPIN's representative: blocks sorted by number
            for a, v in zip(group, sorted(vec[x] for x in group)):
                vec[a] = v
        key = (state[0], *vec)
        if key not in seen_initial:
            seen_initial.add(key)
            initials.append((tuple(vec), a_index))
    if any(state[0] != 0 for state, _b, _g in core.initial_states()):
        raise ExportError("an initial state with the clock phase not 0")

    width = core.width
    done = 0
    for ci, tc in enumerate(classes):
        lead = tc.leader
        start, n = starts[lead], lens[lead]
        q = queues[ci]
        while q:
            phase, b = q.popleft()
            done += 1
            if progress is not None and done % 4096 == 0:
                progress(done)
            blk = tc.blocks[b]
            vec = [0] * width
            vec[start:start + n] = blk
            mode = COARSE if phase % spu == 0 else NORMAL
            nphase = (phase + 1) % spu
            succ: list[int] = []
            if (mode, b) not in tc.base:
                (bblk, bad, good), mv = core.moves(lead, tuple(vec), mode)
                b2, _n = tc.number(tuple(bblk))
                tc.base[(mode, b)] = (b2, _mask(bad, bit), _mask(good, bit))
                rows: list[tuple[int, int, int, int]] = []
                for c, mblk, x, y in mv:
                    m2, _n = tc.number(tuple(mblk))
                    rows.append((local_of[ci][c], m2, _mask(x, bit), _mask(y, bit)))
                tc.moves[(mode, b)] = rows
            succ.append(tc.base[(mode, b)][0])
            succ.extend(r[1] for r in tc.moves[(mode, b)])
            while len(tc.busy) < len(tc.blocks):
                tc.busy.append(bool(core._busy[tc.blocks[len(tc.busy)][0]]))  # queued requests or held events
            if core.has_prescan and not tc.busy[b]:
                if b not in tc.prescan:
                    a2, t2, pb, pg = core._block(lead, blk[0], list(blk[1:]), PRESCAN, 0, 0, None)  # the core's block scan
                    p2, _n = tc.number((a2, *t2))
                    tc.prescan[b] = (p2, _mask(pb, bit), _mask(pg, bit))
                succ.append(tc.prescan[b][0])
            for s in succ:
                if (nphase, s) not in seen[ci]:
                    seen[ci].add((nphase, s))
                    q.append((nphase, s))
        while len(tc.busy) < len(tc.blocks):
            tc.busy.append(bool(core._busy[tc.blocks[len(tc.busy)][0]]))  # as above
    if core.has_prescan:
        for tc in classes:  # a prescan successor of every block another block may meet
            for b in range(len(tc.blocks)):
                if not tc.busy[b] and b not in tc.prescan:
                    blk = tc.blocks[b]
                    a2, t2, pb, pg = core._block(tc.leader, blk[0], list(blk[1:]), PRESCAN, 0, 0, None)  # as above
                    p2, new = tc.number((a2, *t2))
                    tc.prescan[b] = (p2, _mask(pb, bit), _mask(pg, bit))
                    if new:
                        raise ExportError("a prescan pass leads out of the axis's explored blocks")
    names = [_ident(name) for name, _g in model.axis_defs]
    return PromelaModel("", model, core, classes, class_of, alphabet, asserted, initials, names)


# --------------------------------------------------------------------------- text


_IDENT = re.compile(r"[^A-Za-z0-9_]")
_PROMELA_KEYWORDS = frozenset({
    "active", "assert", "atomic", "bit", "bool", "break", "byte", "chan", "d_step", "D_proctype", "do", "else",
    "empty", "enabled", "eval", "false", "fi", "full", "goto", "hidden", "if", "init", "int", "len", "mtype",
    "nempty", "never", "nfull", "od", "of", "pc_value", "printf", "priority", "proctype", "provided", "run",
    "short", "skip", "timeout", "true", "typedef", "unless", "unsigned", "xr", "xs", "c_code", "c_decl", "c_expr",
    "c_state", "c_track", "local", "show", "select", "trace", "notrace", "inline",
})


def _ident(text: str) -> str:
    s = _IDENT.sub("_", text)
    if not s or s[0].isdigit():
        s = "_" + s
    if s in _PROMELA_KEYWORDS:
        s = s + "_"
    return s


def _c_string(text: str) -> str:
    """A C / Promela string literal's contents (no quotes, no format directives)."""
    return "".join(ch if (ch.isascii() and ch.isprintable() and ch not in '"\\%') else "_" for ch in text)


def _array(ctype: str, name: str, values: Sequence[int], suffix: str = "") -> str:
    body = []
    line: list[str] = []
    for v in values:
        line.append(f"{v}{suffix}")
        if len(line) == 24:
            body.append(",".join(line))
            line = []
    if line:
        body.append(",".join(line))
    if not body:
        body = ["0"]
    return f"static const {ctype} {name}[] = {{\n  " + ",\n  ".join(body) + "\n};"


#: entries of one chunk of a table (SPIN copies a c_decl block of at most 64 kB)
CHUNK_SHIFT = 11


def _zero_name(ctype: str) -> str:
    return "mc_zero_" + ctype.replace(" ", "_")


def _table(ctype: str, name: str, values: Sequence[int], suffix: str = "", side: list[str] | None = None) -> str:
    """A large constant table as ``c_decl`` blocks of one chunk each, and ``name``, the
    array of its chunks (read with ``MC_AT(name, i)``); chunks of zeros share one.  With
    ``side``, the definitions go to that list (the tables' C file) and the model gets
    the declaration."""
    size = 1 << CHUNK_SHIFT
    if side is not None:
        chunks = []
        for k in range(0, max(len(values), 1), size):
            part = values[k:k + size]
            if not any(part):
                chunks.append(_zero_name(ctype))
                continue
            cname = f"{name}_{k >> CHUNK_SHIFT}"
            chunks.append(cname)
            side.append(_array(ctype, cname, part, suffix).replace("static const", "const", 1))
        side.append("const " + ctype + " *const " + name + "[] = {" + ", ".join(chunks) + "};")
        return "c_decl {\nextern const " + ctype + " *const " + name + "[];\n}"
    blocks = []
    chunks = []
    for k in range(0, max(len(values), 1), size):
        part = values[k:k + size]
        if not any(part):
            chunks.append(_zero_name(ctype))
            continue
        cname = f"{name}_{k >> CHUNK_SHIFT}"
        chunks.append(cname)
        blocks.append("c_decl {\n" + _array(ctype, cname, part, suffix) + "\n}")
    blocks.append("c_decl {\nstatic const " + ctype + " *const " + name + "[] = {" + ", ".join(chunks) + "};\n}")
    return "\n".join(blocks)


#: table entries above which the tables go to a C file of their own
SIDE_TABLES_ABOVE = 200_000


def build(model: Model, *, progress: Callable[[int], None] | None = None, side_tables: bool | None = None
          ) -> PromelaModel:
    """The Promela model of ``model`` (see the module's docstring)."""
    import time

    t0 = time.perf_counter()
    pm = compute_tables(model, progress=progress)
    entries = sum(len(tc.blocks) * (12 + 2 * len(model.slots)) + 4 * sum(len(r) for r in tc.moves.values())
                  for tc in pm.classes)
    pm.side_tables = entries > SIDE_TABLES_ABOVE if side_tables is None else side_tables
    pm.text = _emit(pm)
    pm.seconds = time.perf_counter() - t0
    return pm


def _emit(pm: PromelaModel) -> str:
    model, core = pm.model, pm.core
    sd = model.sysdef
    naxes = core.naxes
    ntags = len(model.slots)
    names = pm.names
    props = pm.properties
    out: list[str] = []
    w = out.append
    w(f"/* {FORMAT}: system {sd.name}, generated by `motionchart export --format promela`.")
    w(f"   {naxes} axis(es), {ntags} tag(s), {len(model.choices)} inputs, {pm.blocks} blocks in "
      f"{len(pm.classes)} table class(es), {len(props)} asserted properties.")
    if pm.side_tables:
        w("   Its tables are C arrays in TABLES.c: cc -c -O0 TABLES.c && spin -a model.pml &&")
        w("   cc -O2 -DSAFETY -DNOREDUCE -DBFS -o pan pan.c TABLES.o && ./pan -c0 -e")
    else:
        w("   Verify: spin -a model.pml && cc -O2 -DSAFETY -DNOREDUCE -DBFS -o pan pan.c && ./pan -c0 -e")
    w("   Replay a trail: ./pan -r model.pml1.trail (the MC lines name each scan's input). */")
    w("")
    # defines: axes, inputs, states, error codes, properties
    w("/* axes (index into blk[], state[]) */")
    for ai, nm in enumerate(names):
        w(f"#define {nm} {ai}")
    w(f"#define NAXES {naxes}")
    w(f"#define SCANS_PER_UPDATE {core.spu}")
    w("")
    w("/* inputs of each axis (local numbers) */")
    used_defines: set[str] = set(names)
    input_names: list[list[str]] = []
    for ai in range(naxes):
        row = []
        for k, c in enumerate(pm.alphabet[ai]):
            nm = _ident(f"{names[ai]}_{model.choices[c].label()}")
            base_nm = nm
            j = 2
            while nm in used_defines:
                nm = f"{base_nm}_{j}"
                j += 1
            used_defines.add(nm)
            row.append(nm)
            w(f"#define {nm} {k}")
        input_names.append(row)
    w("")
    # leaf states as mtype
    state_names: dict[tuple[str, str], str] = {}
    for axis in model.axes:
        for s in axis.chart.leaf_states():
            key = (axis.chart.id, s.id)
            if key not in state_names:
                nm = _ident(f"{axis.chart.id}_{s.id}")
                while nm in used_defines:
                    nm += "_"
                used_defines.add(nm)
                state_names[key] = nm
    mtype_list = list(state_names.values())
    if len(mtype_list) > 250:
        raise ExportError(f"{len(mtype_list)} leaf states; Promela's mtype holds at most 255 names")
    mtype_no = {nm: len(mtype_list) - k for k, nm in enumerate(mtype_list)}  # SPIN numbers mtype names from the last, from 1
    w("/* leaf states of the charts (state[] holds the axis's) */")
    w("mtype = { " + ", ".join(mtype_list) + " };")
    w("")
    err_codes = sorted({c.err for s in model.slots for c in (*s.ins.checks, *s.ins.aborts)})
    if err_codes and ntags:
        w("/* ERR codes the system's instructions can set (err[] holds each tag's) */")
        for code in [0, *err_codes]:
            try:
                ename = model.spec.error(code).name
            except KeyError:
                ename = f"CODE_{code}"
            nm = _ident(f"ERR_{ename}")
            if nm not in used_defines:
                used_defines.add(nm)
                w(f"#define {nm} {code}")
        for ti, s in enumerate(model.slots):
            nm = _ident(f"TAG_{s.tag.name}")
            used_defines.add(nm)
            w(f"#define {nm} {ti}  /* {s.ins.id} on {model.axis_defs[s.axis_index][0]} */")
        w("")
    w("/* properties: an assert per property; holds_X fails when X is violated (or, for a")
    w("   reachability goal, when the goal is reached: the trail is then its witness) */")
    for k, p in enumerate(props):
        nm = _ident(f"holds_{p.name}")
        used_defines.add(nm)
        w(f"#define {nm} (viol != {k + 1})  /* {p.kind}: {_c_string(p.name)} */")
    w("")
    # state vector
    w("/* the state vector: the clock phase, each axis's block number, and read-outs of the")
    w("   blocks (functions of them, so they add no states) */")
    first = pm.initials[0][0]
    w("byte phase = 0;")
    most = max(len(tc.blocks) for tc in pm.classes)
    ptype, ctype = ("byte", "uchar") if most <= 255 else ("short", "short") if most <= 32767 else ("int", "int")
    tag_vars = []
    for ai in range(naxes):
        tc = pm.classes[pm.class_of[ai]]
        blk = tc.blocks[first[ai]]
        part = core.parts.values[blk[0]]
        leaf = state_names[(model.axes[ai].chart.id, model.axes[ai].c.leaf(part[0]).id)]
        w(f"{ptype} blk_{names[ai]} = {first[ai]};")
        w(f"mtype state_{names[ai]} = {leaf};")
    for s in model.slots:
        nm = _ident(f"err_{s.tag.name}")
        while nm in used_defines:
            nm += "_"
        used_defines.add(nm)
        tag_vars.append(nm)
        ai = s.axis_index
        blk = pm.classes[pm.class_of[ai]].blocks[first[ai]]
        vals = core.tags.values[blk[1 + s.local]][0]
        v = vals[s.fields.index("ERR")] if "ERR" in s.fields else 0
        w(f"byte {nm} = {int(v) & 0xFF if isinstance(v, int) else 0};")
    w("byte viol = 0;  /* set and cleared within a step */")
    w("")
    # C tables
    w("c_decl {")
    w("typedef unsigned long long mc_mask;")
    w(f"#define MC_AT(t, i) ((t)[(i) >> {CHUNK_SHIFT}][(i) & {(1 << CHUNK_SHIFT) - 1}])")
    w("typedef const int *const *mc_ints; typedef const mc_mask *const *mc_masks;")
    w("typedef const unsigned short *const *mc_shorts; typedef const unsigned char *const *mc_bytes;")
    w("typedef struct {")
    w("  int nb; mc_ints base[2]; mc_masks bbad[2]; mc_masks bgood[2];")
    w("  mc_ints moff[2]; mc_shorts mch; mc_ints mto; mc_masks mbad; mc_masks mgood;")
    w("  mc_ints pre; mc_masks pbad; mc_masks pgood; mc_bytes busy;")
    w("  mc_bytes leaf; mc_bytes err; int ntags;")
    w("} mc_class;")
    side: list[str] | None = [] if pm.side_tables else None
    for zt in ("int", "mc_mask", "unsigned short", "unsigned char"):
        if side is None:
            w(f"static const {zt} {_zero_name(zt)}[{1 << CHUNK_SHIFT}];")
        else:
            side.append(f"const {zt} {_zero_name(zt)}[{1 << CHUNK_SHIFT}];")
    w("}")
    class_structs = []
    for ci, tc in enumerate(pm.classes):
        nb = len(tc.blocks)
        lead = tc.leader
        tis = core.tis[lead]
        chart = model.axes[lead].chart
        mch: list[int] = []
        mto: list[int] = []
        mbad: list[int] = []
        mgood: list[int] = []
        for mode in (NORMAL, COARSE):
            base = [-1] * nb
            bbad = [0] * nb
            bgood = [0] * nb
            moff = [0] * (nb + 1)
            for b in range(nb):
                moff[b] = len(mch)
                r = tc.base.get((mode, b))
                if r is not None:
                    base[b], bbad[b], bgood[b] = r
                for c, b2, x, y in tc.moves.get((mode, b), ()):
                    mch.append(c)
                    mto.append(b2)
                    mbad.append(x)
                    mgood.append(y)
            moff[nb] = len(mch)
            w(_table("int", f"mc{ci}_base{mode}", base, side=side))
            w(_table("mc_mask", f"mc{ci}_bbad{mode}", bbad, "ULL", side=side))
            w(_table("mc_mask", f"mc{ci}_bgood{mode}", bgood, "ULL", side=side))
            w(_table("int", f"mc{ci}_moff{mode}", moff, side=side))
        w(_table("unsigned short", f"mc{ci}_mch", mch, side=side))
        w(_table("int", f"mc{ci}_mto", mto, side=side))
        w(_table("mc_mask", f"mc{ci}_mbad", mbad, "ULL", side=side))
        w(_table("mc_mask", f"mc{ci}_mgood", mgood, "ULL", side=side))
        pre = [-1] * nb
        pbad = [0] * nb
        pgood = [0] * nb
        for b, (p2, x, y) in tc.prescan.items():
            pre[b], pbad[b], pgood[b] = p2, x, y
        w(_table("int", f"mc{ci}_pre", pre, side=side))
        w(_table("mc_mask", f"mc{ci}_pbad", pbad, "ULL", side=side))
        w(_table("mc_mask", f"mc{ci}_pgood", pgood, "ULL", side=side))
        w(_table("unsigned char", f"mc{ci}_busy", [int(x) for x in tc.busy], side=side))
        leaves: list[int] = []
        errs: list[int] = []
        for blk in tc.blocks:
            part = core.parts.values[blk[0]]
            leaves.append(mtype_no[state_names[(chart.id, model.axes[lead].c.leaf(part[0]).id)]])
            for j, ti in enumerate(tis):
                fields = model.slots[ti].fields
                vals = core.tags.values[blk[1 + j]][0]
                v = vals[fields.index("ERR")] if "ERR" in fields else 0
                errs.append(int(v) & 0xFF if isinstance(v, int) else 0)
        w(_table("unsigned char", f"mc{ci}_leaf", leaves, side=side))
        w(_table("unsigned char", f"mc{ci}_err", errs, side=side))
        fields_c = [str(nb), f"{{mc{ci}_base0, mc{ci}_base1}}", f"{{mc{ci}_bbad0, mc{ci}_bbad1}}",
                  f"{{mc{ci}_bgood0, mc{ci}_bgood1}}", f"{{mc{ci}_moff0, mc{ci}_moff1}}", f"mc{ci}_mch",
                  f"mc{ci}_mto", f"mc{ci}_mbad", f"mc{ci}_mgood", f"mc{ci}_pre", f"mc{ci}_pbad", f"mc{ci}_pgood",
                  f"mc{ci}_busy", f"mc{ci}_leaf", f"mc{ci}_err", str(len(tis))]
        class_structs.append("{" + ", ".join(fields_c) + "}")
    w("c_decl {")
    w("static const mc_class mc_classes[] = {\n  " + ",\n  ".join(class_structs) + "\n};")
    w(_array("int", "mc_class_of", pm.class_of))
    tag_first = []
    n = 0
    for ai in range(naxes):
        tag_first.append(n)
        n += len(core.tis[ai])
    w(_array("int", "mc_tag_first", tag_first))
    groups = list(core.symmetric_groups)
    gflat = [a for g in groups for a in g]
    goff = [0]
    for g in groups:
        goff.append(goff[-1] + len(g))
    w(_array("int", "mc_group_axes", gflat))
    w(_array("int", "mc_group_off", goff))
    w(f"#define MC_NGROUPS {len(groups)}")
    w(f"#define MC_NPROPS {len(props)}")
    w(f"#define MC_HAS_PRESCAN {int(core.has_prescan)}")
    dead = [k for k, p in enumerate(props) if p.kind == "deadlock_free"]
    w(f"#define MC_DEADLOCK_BIT {dead[0] if dead else -1}")
    w(f"#define MC_DEADLOCK_MASK {(1 << dead[0]) if dead else 0}ULL")
    w("static unsigned char mc_seen[MC_NPROPS + 1];")
    w("static mc_mask mc_bad, mc_good;")
    w("}")
    w("")
    w("c_code {")
    w(f"static {ctype} *mc_blk[NAXES] = {{" + ", ".join(f"&now.blk_{nm}" for nm in names) + "};")
    w("static uchar *mc_state[NAXES] = {" + ", ".join(f"&now.state_{nm}" for nm in names) + "};")
    w("static uchar *mc_err[" + str(max(ntags, 1)) + "] = {" + (", ".join(f"&now.{nm}" for nm in tag_vars) or "0") + "};")
    w("}")
    w(_C_FUNCTIONS)
    w("")
    w("/* fire(k): property k failed (or goal k was reached) in this step, first time in this run */")
    w("inline checks() {")
    for k, p in enumerate(props):
        w(f"  c_code {{ now.viol = mc_fire({k}); }};")
        w(f"  assert({_ident('holds_' + p.name)});")
    w("  viol = 0")
    w("}")
    w("")
    w("active proctype scan() {")
    w("  do")
    w("  :: d_step { c_code { mc_step(-1, 0); }; printf(\"MC step -1 0 scan\\n\"); checks() }")
    if core.has_prescan:
        w("  :: d_step { c_expr { mc_prescan_offered () } -> c_code { mc_prescan(); }; "
          "printf(\"MC prescan\\n\"); checks() }")
    for ai in range(naxes):
        for k, nm in enumerate(input_names[ai]):
            label = _c_string(model.choices[pm.alphabet[ai][k]].label())
            w(f"  :: d_step {{ c_expr {{ mc_offered ({ai}, {nm}) }} -> c_code {{ mc_step({ai}, {nm}); }}; "
              f"printf(\"MC step {ai} {k} {label} ({names[ai]})\\n\"); checks() }}")
    for j in range(1, len(pm.initials)):
        w(f"  :: d_step {{ c_expr {{ mc_at_start () }} -> c_code {{ mc_start({j}); }}; "
          f"printf(\"MC initial {j}\\n\"); checks() }}  /* configuration assignment {pm.initials[j][1]} */")
    w("  od")
    w("}")
    # initial states (C, after the state vector exists)
    init_rows = [v for v, _a in pm.initials]
    text = "\n".join(out) + "\n"
    inits = "c_decl {\n" + _array("int", "mc_initial", [b for row in init_rows for b in row]) + "\n}\n"
    if side is not None:
        pm.tables = (f"/* {FORMAT}: the tables of the model of system {sd.name}; compile with pan.c: "
                     "cc ... -o pan pan.c TABLES.c */\n"
                     "typedef unsigned long long mc_mask;\n" + "\n".join(side) + "\n")
    return text.replace("c_decl {\ntypedef", inits + "c_decl {\ntypedef", 1)


_C_FUNCTIONS = r"""c_code {
void wrapup(void);
#ifndef MC_STOP_AFTER
#define MC_STOP_AFTER 0  /* end the search once this many properties are decided (0: never) */
#endif
static int mc_found;
static void mc_enough(void) { if (MC_STOP_AFTER > 0 && mc_found >= MC_STOP_AFTER) wrapup(); }
static void mc_readout(void) {
  int a, j;
  for (a = 0; a < NAXES; a++) {
    const mc_class *c = &mc_classes[mc_class_of[a]];
    int b = *mc_blk[a];
    *mc_state[a] = MC_AT(c->leaf, b);
    for (j = 0; j < c->ntags; j++)
      *mc_err[mc_tag_first[a] + j] = MC_AT(c->err, b * c->ntags + j);
  }
}
static void mc_sort(void) {
  int g, i, k;
  for (g = 0; g < MC_NGROUPS; g++) {
    for (i = mc_group_off[g] + 1; i < mc_group_off[g + 1]; i++) {
      int v = *mc_blk[mc_group_axes[i]];
      for (k = i; k > mc_group_off[g] && *mc_blk[mc_group_axes[k - 1]] > v; k--)
        *mc_blk[mc_group_axes[k]] = *mc_blk[mc_group_axes[k - 1]];
      *mc_blk[mc_group_axes[k]] = v;
    }
  }
}
static int mc_find(int a, int mode, int local) {
  const mc_class *c = &mc_classes[mc_class_of[a]];
  int b = *mc_blk[a], m;
  for (m = MC_AT(c->moff[mode], b); m < MC_AT(c->moff[mode], b + 1); m++)
    if (MC_AT(c->mch, m) == local) return m;
  return -1;
}
static int mc_mode(void) { return (now.phase % SCANS_PER_UPDATE) == 0 ? 1 : 0; }
static int mc_offered(int a, int local) { return mc_find(a, mc_mode(), local) >= 0; }
static void mc_dead_check(void);
static void mc_step(int axis, int local) {
  int mode = mc_mode(), a, nb[NAXES];
  mc_enough();
  mc_bad = 0; mc_good = 0;
  for (a = 0; a < NAXES; a++) {
    const mc_class *c = &mc_classes[mc_class_of[a]];
    int b = *mc_blk[a];
    if (a == axis) {
      int m = mc_find(a, mode, local);
      nb[a] = MC_AT(c->mto, m); mc_bad |= MC_AT(c->mbad, m); mc_good |= MC_AT(c->mgood, m);
    } else {
      nb[a] = MC_AT(c->base[mode], b);
      if (axis < 0) { mc_bad |= MC_AT(c->bbad[mode], b); mc_good |= MC_AT(c->bgood[mode], b); }
    }
    if (nb[a] < 0) { printf("motionchart: block %d of axis %d has no step in mode %d\n", b, a, mode); nb[a] = b; }
  }
  for (a = 0; a < NAXES; a++) *mc_blk[a] = nb[a];
  now.phase = (now.phase + 1) % SCANS_PER_UPDATE;
  mc_sort();
  mc_readout();
  mc_dead_check();
}
static int mc_prescan_offered(void) {
  int a;
  for (a = 0; a < NAXES; a++)
    if (MC_AT(mc_classes[mc_class_of[a]].busy, *mc_blk[a])) return 0;
  return MC_HAS_PRESCAN;
}
static void mc_prescan(void) {
  int a;
  mc_enough();
  mc_bad = 0; mc_good = 0;
  for (a = 0; a < NAXES; a++) {
    const mc_class *c = &mc_classes[mc_class_of[a]];
    int b = *mc_blk[a];
    *mc_blk[a] = MC_AT(c->pre, b); mc_bad |= MC_AT(c->pbad, b); mc_good |= MC_AT(c->pgood, b);
  }
  now.phase = (now.phase + 1) % SCANS_PER_UPDATE;
  mc_sort();
  mc_readout();
  mc_dead_check();
}
/* a state is a deadlock when every successor is the state itself */
static void mc_dead_check(void) {
  int a, m, mode, pre;
  if (MC_DEADLOCK_BIT < 0 || SCANS_PER_UPDATE != 1) return;
  mode = mc_mode();
  pre = mc_prescan_offered();
  for (a = 0; a < NAXES; a++) {
    const mc_class *c = &mc_classes[mc_class_of[a]];
    int b = *mc_blk[a];
    if (MC_AT(c->base[mode], b) != b) return;
    for (m = MC_AT(c->moff[mode], b); m < MC_AT(c->moff[mode], b + 1); m++)
      if (MC_AT(c->mto, m) != b) return;
    if (pre && MC_AT(c->pre, b) != b) return;
  }
  mc_bad |= MC_DEADLOCK_MASK;
}
static int mc_at_start(void) {
  int a;
  if (now.phase != 0) return 0;
  for (a = 0; a < NAXES; a++) if (*mc_blk[a] != mc_initial[a]) return 0;
  return 1;
}
static void mc_start(int k) {
  int a;
  mc_bad = 0; mc_good = 0;  /* the initial states' properties are decided before the search */
  now.phase = 0;
  for (a = 0; a < NAXES; a++) *mc_blk[a] = mc_initial[k * NAXES + a];
  mc_sort();
  mc_readout();
  mc_dead_check();
}
static int mc_fire(int k) {
  if (((mc_bad | mc_good) >> k) & 1ULL) {
    if (!mc_seen[k]) { mc_seen[k] = 1; mc_found++; return k + 1; }
  }
  return 0;
}
}"""
