"""Ladder programs as input: readers for ASCII rungs, neutral text and L5X, one program IR, the interpreter.

Pipeline position: beside the specification.  A reader per source form
(:mod:`~statecharts.program.rungtext`, :mod:`~statecharts.program.l5x`, dispatched by
:func:`load_program`) gives one frozen :class:`Program`; :class:`Ladder` runs it inside
the scan module (:class:`statecharts.scan.System`), where its motion instructions are
the specification's instruction charts; :class:`Controller` is the API for one's own
code and tests, and :mod:`statecharts.program.strategies` holds hypothesis strategies.
See ``docs/programs.md``.
"""

from statecharts.program.api import Controller
from statecharts.program.ir import Program
from statecharts.program.ladder import Ladder, ProgramFault
from statecharts.program.reader import ProgramError, load_program

__all__ = ["Controller", "Ladder", "Program", "ProgramError", "ProgramFault", "load_program"]
