"""The argument parser of every machinesim command and scenario."""

from __future__ import annotations

import argparse
import difflib
import re
import sys

from machinesim.units import typed_float

#: A value that starts like a negative number: ``-707,-707``, ``-1e-3``, ``-.5``, and
#: ``-inf``, ``-nan``, which the option's own check refuses, naming them.
_NEGATIVE = re.compile(r"-(?:\.?\d|inf|nan)", re.IGNORECASE)
#: Options that may be given more than once: each adds to what the others gave (``--roi``,
#: ``--vary``), or ends the command (``--help``, ``--version``). argparse keeps the last of
#: any other and drops the rest without a word.
_REPEATABLE = (argparse._AppendAction, argparse._AppendConstAction, argparse._CountAction,
               argparse._ExtendAction, argparse._HelpAction, argparse._VersionAction)


class ArgumentParser(argparse.ArgumentParser):
    """An argument parser whose usage errors name an option the command line misspelt, with
    the one it resembles (``--tol is not an option here; did you mean --tool?``).

    argparse hands an unknown option of a subcommand on and reports first the required
    option it then misses: ``--tol v:90`` ended in "the following arguments are required:
    --tool", naming neither the word typed nor the one meant. Subparsers made from this
    parser are of this class too, and each reads the words it was handed.

    An option that takes a value given twice is a usage error naming both (`_repeated`):
    argparse kept the last, so ``--seed 1 --seed 2`` ran seed 2 without a word. Options
    that add up (``action="append"``) and switches (``--quiet``) may be repeated."""

    _words: tuple[str, ...] = ()

    def parse_known_args(self, args=None, namespace=None):
        self._words = tuple(sys.argv[1:] if args is None else map(str, args))
        words = self._joined(self._words)
        repeated = self._repeated(words)
        if repeated:  # argparse's own error: no misspelling hint for an abbreviation
            argparse.ArgumentParser.error(self, repeated)
        return super().parse_known_args(words, namespace)

    def _repeated(self, words: list[str]) -> str | None:
        """The usage error for the first of this parser's single-valued options that
        ``words`` give more than once (as typed, each with its value), or None. A
        subcommand's words are its own parser's to check (argparse hands them on); an
        option abbreviated as argparse takes it (``--see`` for ``--seed``) counts."""
        strings = {s: action for action in self._actions for s in action.option_strings}
        commands = {c for action in self._actions
                    if isinstance(action, argparse._SubParsersAction) for c in action.choices}
        given: dict[argparse.Action, list[str]] = {}
        for k, word in enumerate(words):
            if word == "--" or word in commands:
                break
            name = word.split("=", 1)[0] if word.startswith("--") else word
            action = strings.get(name)
            if action is None and name.startswith("--") and self.allow_abbrev:
                matches = {strings[s] for s in strings if s.startswith(name)}
                action = matches.pop() if len(matches) == 1 else None
            if action is None or isinstance(action, _REPEATABLE) or (
                    action.nargs == 0 and not isinstance(action, argparse.BooleanOptionalAction)):
                continue  # a switch given twice (--quiet --quiet) means what it says once
            takes_value = action.nargs != 0 and "=" not in word and k + 1 < len(words)
            given.setdefault(action, []).append(f"{word} {words[k + 1]}" if takes_value
                                                else word)
        for action, typed in given.items():
            if len(typed) > 1:
                return (f"argument {'/'.join(action.option_strings)}: given {len(typed)} "
                        f"times ({', '.join(typed)}); give it once: only the last would count")
        return None

    def _joined(self, words) -> list[str]:
        """``--option -707,-707`` as ``--option=-707,-707`` for an option that takes one
        value: argparse takes a word that starts with '-' for an option unless it is a
        plain negative number (``-178``), so a negative first component (``--c-offset-um
        -707,-707``, ``--e-ys-um -1e3``) ended in "expected one argument", and so did
        ``--r-mm -inf``, which the option's check refuses as not finite."""
        valued = {s for action in self._actions if action.nargs is None
                  for s in action.option_strings}
        out: list[str] = []
        for k, word in enumerate(words):
            if out and out[-1] in valued and _NEGATIVE.match(word) and "--" not in words[:k]:
                out[-1] = f"{out[-1]}={word}"
            else:
                out.append(word)
        return out

    def error(self, message: str):
        words = self._words
        known = [s for action in self._actions for s in action.option_strings]
        for action in self._actions:  # the top parser: add the options of the command given
            if isinstance(action, argparse._SubParsersAction):
                command = next((w for w in words if w in action.choices), None)
                if command is not None:
                    known += [s for a in action.choices[command]._actions
                              for s in a.option_strings]
        hints = []
        for word in words:
            option = word.split("=", 1)[0]
            if option.startswith("--") and option not in known:
                close = difflib.get_close_matches(option, known, n=1, cutoff=0.6)
                if close:
                    hints.append(f"{option} is not an option here; did you mean {close[0]}?")
        super().error("; ".join([message, *hints]))


def typed_number(text: str) -> float:
    """An argparse type for a number option (a scenario's ``--r-mm``, ``--chord-nm``,
    ``view --duration``): ``text`` as a float when written as a plain number
    (`machinesim.units.typed_float`), refused as the command line's error otherwise.
    float() read '0_5' as 5 (``--e-ys-um 0_5``: 5 um) and full-width digits ('１２０') as
    120. Whether the value is finite and in range is the command's to say, in its terms."""
    try:
        return typed_float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a number (ASCII digits, a point, an exponent: 120.555, -1.78e2), "
            f"got {text!r}") from None
