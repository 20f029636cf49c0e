"""Hand-written tests of each non-motion ladder instruction against documented Logix behaviour.

Every expectation cites its source: the execution tables and flowcharts of the Logix 5000
General Instructions Reference Manual, 1756-RM003N-EN-P (October 2011), by page, or an
interpretation recorded in docs/semantics.md ("Ladder programs", INT-Pnn).  The programs
run without axes, on the scan module, with a 10 ms scan unless a test says otherwise.
"""

from __future__ import annotations

import pytest

from statecharts.loader import load_spec
from statecharts.program.ladder import Ladder, ProgramFault
from statecharts.program.reader import parse_program_text
from statecharts.scan import ScanInputs, System


@pytest.fixture(scope="module")
def spec():
    return load_spec()


class Run:
    """A neutral-text program on a system without axes."""

    def __init__(self, spec, text: str, *, scan_ms: int = 10) -> None:
        self.ladder = Ladder(parse_program_text("test.txt", text, spec=spec, form="neutral"))
        self.system = System(spec, [], [], scan_ms=scan_ms, coarse_update_ms=scan_ms, ladder=self.ladder)

    def scan(self, **writes: object) -> Run:
        self.system.scan(ScanInputs(writes=writes))
        return self

    def prescan(self) -> Run:
        self.system.scan(ScanInputs(prescan=True))
        return self

    def __getitem__(self, path: str) -> object:
        return self.ladder.read(path)

    def set(self, path: str, value: object) -> Run:
        self.ladder.write(path, value)
        return self


# -- bit instructions (RM003N chapter 2) ---------------------------------------------------


def test_xic_xio_and_ote(spec) -> None:
    r = Run(spec, "XIC(A)XIO(B)OTE(C);")
    assert r.scan(A=True)["C"] is True  # ch. 2 (XIC, XIO): XIC true when the bit is set, XIO when it is clear
    assert r.scan(B=True)["C"] is False  # p96: OTE clears its bit when the rung is false


def test_prescan_clears_ote_and_keeps_otl(spec) -> None:
    r = Run(spec, "XIC(A)OTE(C);XIC(A)OTL(L);")
    r.scan(A=True)
    assert r["C"] is True and r["L"] is True
    r.prescan()
    assert r["C"] is False  # p96: prescan clears the OTE's data bit
    assert r["L"] is True  # ch. 2 (OTL): prescan does not modify the OTL's data bit


def test_otl_otu_retain_when_the_rung_is_false(spec) -> None:
    r = Run(spec, "XIC(S)OTL(L);XIC(R)OTU(L);")
    assert r.scan(S=True)["L"] is True
    assert r.scan(S=False)["L"] is True  # ch. 2 (OTL): rung false, OTL leaves the bit
    assert r.scan(R=True)["L"] is False  # p100: OTU clears it
    assert r.scan(R=False)["L"] is False  # p100: rung false, OTU leaves it


def test_ons_storage_bit(spec) -> None:
    r = Run(spec, "XIC(A)ONS(S)OTE(Q);")
    r.prescan()
    assert r["S"] is True  # p103: prescan sets the storage bit
    assert r.scan(A=True)["Q"] is False  # so a rung already true does not trigger on the first scan
    assert r.scan(A=False)["S"] is False  # p103: rung false clears the storage bit
    assert r.scan(A=True)["Q"] is True  # false-to-true: rung-condition-out true for one scan
    assert r["S"] is True
    assert r.scan()["Q"] is False  # storage bit still set: rung-condition-out false


def test_osr_and_osf(spec) -> None:
    r = Run(spec, "XIC(A)OSR(SR,QR);XIC(A)OSF(SF,QF);")
    r.prescan()
    assert (r["SR"], r["QR"], r["SF"], r["QF"]) == (True, False, False, False)  # ch. 2 OSR/OSF prescan rows (also Rockwell's OSR/OSF reference pages)
    r.scan(A=True)
    assert r["QR"] is False  # storage set by prescan: no rising edge on the first scan
    r.scan(A=False)
    assert (r["QR"], r["QF"]) == (False, True)  # OSF: true-to-false sets the output for one scan
    assert r.scan()["QF"] is False
    r.scan(A=True)
    assert r["QR"] is True  # OSR: false-to-true
    assert r.scan()["QR"] is False


def test_branches(spec) -> None:
    r = Run(spec, "XIC(A)[XIC(B)OTE(X),XIC(C)OTE(Y),]OTE(Z);")
    r.scan(A=True, B=True)
    # each leg gets the condition entering the branch; an instruction in a false leg still
    # runs (the OTE clears its bit); after the branch the rung is true when any leg is
    assert (r["X"], r["Y"], r["Z"]) == (True, False, True)
    r.scan(B=False)
    assert (r["X"], r["Y"], r["Z"]) == (False, False, True)  # the empty leg passes the condition on
    r2 = Run(spec, "[XIC(A),XIC(B)][XIC(C),XIC(D)[XIC(E),XIC(F)]]OTE(Z);")
    r2.scan(B=True, D=True, F=True)
    assert r2["Z"] is True
    r2.scan(F=False)
    assert r2["Z"] is False


# -- timers and counters (RM003N chapter 3) --------------------------------------------------


def test_ton_timing_in_scans_and_ms(spec) -> None:
    r = Run(spec, "XIC(A)TON(T1,50,0);")
    r.prescan()
    r.scan(A=True)
    # p118: the first true scan sets EN and TT and starts timing (ACC not yet advanced)
    assert (r["T1.EN"], r["T1.TT"], r["T1.DN"], r["T1.ACC"]) == (True, True, False, 0)
    for k in range(1, 5):
        r.scan()
        assert (r["T1.ACC"], r["T1.DN"]) == (10 * k, False)  # ACC grows by the scan period
    r.scan()
    assert (r["T1.ACC"], r["T1.DN"], r["T1.TT"]) == (50, True, False)  # ACC >= PRE: DN set, TT cleared
    r.scan()
    assert r["T1.ACC"] == 50  # DN set: no more accumulation
    r.scan(A=False)
    assert (r["T1.EN"], r["T1.DN"], r["T1.ACC"]) == (False, False, 0)  # p118: rung false resets


def test_ton_with_a_25_ms_scan_passes_the_preset(spec) -> None:
    r = Run(spec, "XIC(A)TON(T1,60,0);", scan_ms=25)
    r.scan(A=True).scan().scan()
    assert (r["T1.ACC"], r["T1.DN"]) == (50, False)
    r.scan()
    assert (r["T1.ACC"], r["T1.DN"]) == (75, True)  # p118: DN once ACC >= PRE; ACC is not clipped


def test_ton_prescan_and_negative_preset(spec) -> None:
    r = Run(spec, "XIC(A)TON(T1,50,0);")
    r.scan(A=True).scan()
    r.prescan()
    assert (r["T1.EN"], r["T1.TT"], r["T1.ACC"]) == (False, False, 0)  # p118 prescan row
    r.set("T1.PRE", -1)
    with pytest.raises(ProgramFault, match="type 4, code 34"):  # RM003N TON fault conditions
        r.scan(A=True)


def test_tof(spec) -> None:
    r = Run(spec, "XIC(A)TOF(T1,20,0);")
    r.prescan()
    assert (r["T1.DN"], r["T1.ACC"]) == (False, 20)  # p122: prescan clears DN and sets ACC to PRE
    r.scan(A=True)
    assert (r["T1.EN"], r["T1.DN"], r["T1.ACC"]) == (True, True, 0)  # p122: rung true
    r.scan(A=False)
    assert (r["T1.EN"], r["T1.TT"], r["T1.DN"]) == (False, True, True)  # timing starts
    r.scan()
    assert (r["T1.ACC"], r["T1.DN"]) == (10, True)
    r.scan()
    assert (r["T1.ACC"], r["T1.DN"], r["T1.TT"]) == (20, False, False)  # ACC >= PRE: DN cleared


def test_rto_retains(spec) -> None:
    r = Run(spec, "XIC(A)RTO(T1,30,0);XIC(R)RES(T1);")
    r.scan(A=True).scan()
    assert r["T1.ACC"] == 10
    r.scan(A=False)
    assert (r["T1.ACC"], r["T1.EN"]) == (10, False)  # p127: rung false keeps ACC
    r.scan(A=True).scan().scan()
    assert (r["T1.ACC"], r["T1.DN"]) == (30, True)
    r.prescan()
    assert (r["T1.ACC"], r["T1.DN"]) == (30, False)  # p127: prescan clears EN, TT, DN, keeps ACC
    r.scan(A=False, R=True)
    assert (r["T1.ACC"], r["T1.DN"]) == (0, False)  # ch. 3 (RES): clears ACC and the status bits


def test_ctu_ctd_and_res(spec) -> None:
    r = Run(spec, "XIC(U)CTU(C1,2,0);XIC(D)CTD(C1,2,0);XIC(R)RES(C1);")
    r.prescan()
    assert r["C1.CU"] is True  # p143: prescan sets CU so the first scan does not count
    r.scan(U=True)
    assert r["C1.ACC"] == 0
    r.scan(U=False).scan(U=True)
    assert (r["C1.ACC"], r["C1.DN"]) == (1, False)  # one count per false-to-true transition
    r.scan(U=False).scan(U=True)
    assert (r["C1.ACC"], r["C1.DN"]) == (2, True)  # ACC >= PRE: DN
    r.scan(U=False, D=True)
    assert (r["C1.ACC"], r["C1.DN"]) == (1, False)  # ch. 3 (CTD): counts down, DN follows ACC >= PRE
    r.scan(D=False, R=True)
    assert (r["C1.ACC"], r["C1.CU"], r["C1.CD"]) == (0, False, False)


def test_ctu_overflow_wraps_and_sets_ov(spec) -> None:
    r = Run(spec, "XIC(U)CTU(C1,0,0);")
    r.set("C1.ACC", 2**31 - 1)
    r.scan(U=True)
    assert (r["C1.ACC"], r["C1.OV"]) == (-(2**31), True)  # RM003N p150: rolls over to -2,147,483,648


# -- compare, move, math ---------------------------------------------------------------------


def test_compares_and_lim(spec) -> None:
    r = Run(spec, "EQU(A,3)OTE(E);NEQ(A,3)OTE(N);LES(A,3)OTE(L);LEQ(A,3)OTE(LE);GRT(A,3)OTE(G);GEQ(A,3)OTE(GE);"
                  "LIM(1,A,5)OTE(IN);LIM(5,A,1)OTE(OUT);")
    r.scan(A=3)
    assert [r[x] for x in ("E", "N", "L", "LE", "G", "GE", "IN", "OUT")] == [True, False, False, True, False, True, True, False]
    r.scan(A=7)
    # LIM with Low > High is true outside the band (RM003N Compare chapter, LIM)
    assert [r[x] for x in ("E", "G", "IN", "OUT")] == [False, True, False, True]


def test_integer_destinations_wrap_and_reals_round_half_even(spec) -> None:
    r = Run(spec, "ADD(A,1,S);MOV(R,D);MOV(R2,D2);")
    r.ladder.program.tags  # noqa: B018  # reading the tag table must not fail
    r.scan(A=2147483647, R=2.5, R2=3.5)
    assert r["S"] == -2147483648  # DINT wraps around (two's complement)
    assert (r["D"], r["D2"]) == (2, 4)  # REAL to integer: nearest, halves to even (INT-P07)


def test_div_mod_neg_and_division_by_zero(spec) -> None:
    r = Run(spec, "DIV(A,B,Q);MOD(A,B,M);NEG(A,N);")
    r.scan(A=-7, B=2)
    assert (r["Q"], r["M"], r["N"]) == (-3, -1, 7)  # integers: the quotient truncates; MOD = A - TRN(A/B)*B (p281)
    r.scan(B=0)
    assert (r["Q"], r["M"]) == (-3, -1)  # p277: divisor zero is a minor fault; destination kept (INT-P08)
    assert [f.code for f in r.ladder.minor_faults] == [4, 4]


def test_cpt_and_cmp_expressions(spec) -> None:
    r = Run(spec, "CPT(X,(A+B)*2-A MOD 3);CMP(ABS(A-B)>2 AND NOT F)OTE(C);CPT(Y,16#F0 OR 2#0011);")
    r.scan(A=5, B=1)
    assert r["X"] == 10  # (5+1)*2 - (5 MOD 3) with MOD binding tighter than -
    assert r["C"] is True
    assert r["Y"] == 0xF3
    r.scan(F=True)
    assert r["C"] is False


def test_btd_clr_cop(spec) -> None:
    r = Run(spec, "BTD(S,4,D,0,4);XIC(K)CLR(S);XIC(K)COP(Arr[1],Dst[0],2);MOV(Arr[3],Dst[3]);")
    r.scan(S=0xA5)
    assert r["D"] == 0xA  # bits 4..7 of the source into bits 0..3 of the destination
    r.set("Arr[1]", 11).set("Arr[2]", 22)
    r.scan(K=True)
    assert (r["S"], r["Dst[0]"], r["Dst[1]"]) == (0, 11, 22)


def test_bit_of_word_and_computed_subscripts(spec) -> None:
    r = Run(spec, "XIC(Flags.3)OTE(B3);XIC(G)OTE(Bits[I]);AFI()OTE(Bits[3]);MOV(Arr[I],V);MOV(0,Arr[3]);MOV(9,Arr[2]);")
    r.scan(Flags=8, G=True, I=2)
    assert (r["B3"], r["Bits[2]"]) == (True, True)
    r.scan()
    assert r["V"] == 9
    with pytest.raises(ProgramFault, match="type 4, code 20"):  # subscript out of range: major fault
        r.scan(I=7)


def test_afi_nop_jsr_ret(spec) -> None:
    text = ("AFI()OTE(X);NOP()OTE(Y);XIC(CALL)JSR(Sub,0);\n"
            "ROUTINE Sub\nOTE(InSub);XIC(EARLY)RET();OTE(AfterRet);")
    r = Run(spec, text)
    r.scan(CALL=True)
    assert (r["X"], r["Y"], r["InSub"], r["AfterRet"]) == (False, True, True, True)
    r.scan(EARLY=True)
    assert r["AfterRet"] is True  # RET ends the routine: the later rung is not scanned and keeps its bit
    r.scan(CALL=False, EARLY=False)
    assert r["InSub"] is True  # a routine that is not called is not scanned (its OTE is not cleared)
    r.prescan()
    assert (r["InSub"], r["AfterRet"]) == (False, False)  # prescan reaches the called routine's OTEs
