"""Shell-completion scripts generated from the command tree.

The scripts list every command, option and choice, so completing those never starts
Python. Words that depend on the machine or on the line (driver and emulator names,
diagnostic codes, definition names, element names of the configurations already typed) are
asked of ``gadgetctl __complete KIND WORDS...`` (:mod:`gadgetctl.cli.candidates`), which
answers without loading the CLI framework. ``python -m gadgetctl.cli.completions DIR``
(``make completions``) rewrites the files in ``completions/``; a test fails when they are
stale.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

ROOT = "."
FILES = {"bash": "gadgetctl.bash", "zsh": "_gadgetctl", "fish": "gadgetctl.fish"}

# Positional arguments completed dynamically: command path -> (candidate kind, how many of
# the positional words take it (0: all), whether files are offered as well).
DYNAMIC_ARGUMENTS: dict[str, tuple[str, int, bool]] = {
    "explain": ("codes", 1, False),
    "emulate": ("emulators", 1, False),
    "defs show": ("definitions", 1, False),
    "defs tree": ("definitions", 1, False),
    "drivers load": ("drivers", 0, False),
    "monitor": ("inputs", 0, True),
    "serve": ("inputs", 0, True),
}
# Option values completed dynamically: (command path, option) -> candidate kind.
DYNAMIC_OPTIONS: dict[tuple[str, str], str] = {
    ("monitor", "--keyboard"): "keyboards",
    ("config show", "--element"): "elements",
    ("defs list", "--base"): "definitions",
}


@dataclass
class OptionInfo:
    names: list[str]
    takes_value: bool
    choices: list[str]
    help: str


@dataclass
class CommandInfo:
    path: str
    help: str = ""
    options: list[OptionInfo] = field(default_factory=list)
    subcommands: dict[str, CommandInfo] = field(default_factory=dict)


def command_tree() -> CommandInfo:
    import typer.main

    from gadgetctl.cli.app import build_app

    return _describe(typer.main.get_command(build_app()), ROOT)


def _describe(command, path: str) -> CommandInfo:
    info = CommandInfo(
        path=path, help=(command.help or "").strip().splitlines()[0] if command.help else ""
    )
    for param in command.params:
        if getattr(param, "param_type_name", "") != "option" or getattr(param, "hidden", False):
            continue
        choices = _choices(param)
        info.options.append(
            OptionInfo(
                names=[*param.opts, *param.secondary_opts],
                takes_value=not param.is_flag and not getattr(param, "count", False),
                choices=choices,
                help=(param.help or "").split(". ")[0].rstrip("."),
            )
        )
    info.options.append(OptionInfo(["--help", "-h"], False, [], "Show help and exit"))
    for name, sub in sorted(getattr(command, "commands", {}).items()):
        if not getattr(sub, "hidden", False):
            info.subcommands[name] = _describe(sub, name if path == ROOT else f"{path} {name}")
    return info


def _choices(param) -> list[str]:
    """Choices of an option whose annotation is an Enum (typer's way to declare choices)."""
    from enum import Enum

    choices = getattr(getattr(param, "type", None), "choices", None)
    if choices:
        return [str(getattr(c, "value", c)) for c in choices]
    annotation = getattr(getattr(param, "type_descriptor", None), "annotation", None)
    if isinstance(annotation, type) and issubclass(annotation, Enum):
        return [str(member.value) for member in annotation]
    return []


def _walk(info: CommandInfo):
    yield info
    for sub in info.subcommands.values():
        yield from _walk(sub)


def _quote(text: str) -> str:
    return "'" + text.replace("'", "'\\''") + "'"


def _dynamic_option(path: str, option: OptionInfo) -> str | None:
    return next(
        (DYNAMIC_OPTIONS[(path, n)] for n in option.names if (path, n) in DYNAMIC_OPTIONS), None
    )


def _dynamic_tables(info: CommandInfo) -> tuple[dict[str, str], dict[str, str]]:
    """``"PATH OPTION" -> kind`` for every name of a dynamic option, ``PATH -> "kind max files"``."""
    options = {}
    for node in _walk(info):
        for option in node.options:
            kind = _dynamic_option(node.path, option)
            if kind:
                options.update({f"{node.path} {name}": kind for name in option.names})
    arguments = {
        path: f"{kind} {count} {'files' if files else 'nofiles'}"
        for path, (kind, count, files) in DYNAMIC_ARGUMENTS.items()
    }
    return options, arguments


def _tables(info: CommandInfo) -> tuple[dict[str, str], dict[str, str], dict[str, str], set[str]]:
    subs, opts, choices, value_opts = {}, {}, {}, set()
    for node in _walk(info):
        subs[node.path] = " ".join(node.subcommands)
        opts[node.path] = " ".join(n for o in node.options for n in o.names)
        for option in node.options:
            for name in option.names:
                if option.choices:
                    choices[f"{node.path} {name}"] = " ".join(option.choices)
                elif option.takes_value:
                    value_opts.add(f"{node.path} {name}")
    return subs, opts, choices, value_opts


def bash_script(info: CommandInfo) -> str:
    subs, opts, choices, value_opts = _tables(info)
    dyn_opts, dyn_args = _dynamic_tables(info)
    lines = [
        "# bash completion for gadgetctl (generated by `make completions`; do not edit)",
        "declare -gA _gadgetctl_subs=(",
    ]
    lines += [f"  [{_quote(k)}]={_quote(v)}" for k, v in subs.items()]
    lines += [")", "declare -gA _gadgetctl_opts=("]
    lines += [f"  [{_quote(k)}]={_quote(v)}" for k, v in opts.items()]
    lines += [")", "declare -gA _gadgetctl_choices=("]
    lines += [f"  [{_quote(k)}]={_quote(v)}" for k, v in sorted(choices.items())]
    lines += [")", "declare -gA _gadgetctl_valueopts=("]
    lines += [f"  [{_quote(k)}]=1" for k in sorted(value_opts)]
    lines += [")", "declare -gA _gadgetctl_dynopts=("]
    lines += [f"  [{_quote(k)}]={_quote(v)}" for k, v in sorted(dyn_opts.items())]
    lines += [")", "declare -gA _gadgetctl_dynargs=("]
    lines += [f"  [{_quote(k)}]={_quote(v)}" for k, v in sorted(dyn_args.items())]
    lines += [
        ")",
        r"""
# Candidates of KIND from `gadgetctl __complete KIND WORDS...` (the words before the cursor),
# those starting with the current word; a tab and a description may follow each name.
_gadgetctl_dynamic() {
  local line name prefix=${cur//\\/}
  prefix=${prefix#[\"\']}
  while IFS= read -r line; do
    name=${line%%$'\t'*}
    [[ $name == "$prefix"* ]] && COMPREPLY+=("$name")
  done < <("${COMP_WORDS[0]/#\~/$HOME}" __complete "$1" "${COMP_WORDS[@]:1:COMP_CWORD-1}" 2>/dev/null)
}

_gadgetctl() {
  local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD-1]} path=. i w skip= npos=0
  local kind max files
  COMPREPLY=()
  # bash splits `--opt=VALUE` into `--opt`, `=`, `VALUE` (COMP_WORDBREAKS)
  [[ $prev == = && COMP_CWORD -gt 2 ]] && prev=${COMP_WORDS[COMP_CWORD-2]}
  [[ $cur == = ]] && cur=
  for ((i = 1; i < COMP_CWORD; i++)); do
    w=${COMP_WORDS[i]}
    if [[ -n $skip ]]; then [[ $w == = ]] || skip=; continue; fi
    if [[ $w == -* ]]; then
      if [[ $w != *=* && ( -n ${_gadgetctl_valueopts["$path $w"]+x} || -n ${_gadgetctl_choices["$path $w"]+x} ) ]]; then
        skip=1
      fi
      continue
    fi
    if [[ " ${_gadgetctl_subs[$path]} " == *" $w "* ]]; then
      if [[ $path == . ]]; then path=$w; else path="$path $w"; fi
    else
      ((npos++))
    fi
  done
  if [[ -n ${_gadgetctl_dynopts["$path $prev"]+x} ]]; then
    _gadgetctl_dynamic "${_gadgetctl_dynopts["$path $prev"]}"; return
  fi
  if [[ -n ${_gadgetctl_choices["$path $prev"]+x} ]]; then
    COMPREPLY=($(compgen -W "${_gadgetctl_choices["$path $prev"]}" -- "$cur")); return
  fi
  if [[ -n ${_gadgetctl_valueopts["$path $prev"]+x} ]]; then
    COMPREPLY=($(compgen -f -- "$cur")); return
  fi
  if [[ $cur == -* ]]; then
    COMPREPLY=($(compgen -W "${_gadgetctl_opts[$path]}" -- "$cur")); return
  fi
  if [[ -n ${_gadgetctl_subs[$path]} ]]; then
    COMPREPLY=($(compgen -W "${_gadgetctl_subs[$path]}" -- "$cur")); return
  fi
  if [[ -n ${_gadgetctl_dynargs[$path]+x} ]]; then
    read -r kind max files <<< "${_gadgetctl_dynargs[$path]}"
    if (( max == 0 || npos < max )); then
      _gadgetctl_dynamic "$kind"
      [[ $files == files ]] && COMPREPLY+=($(compgen -f -- "$cur"))
      return
    fi
  fi
  COMPREPLY=($(compgen -f -- "$cur"))
}
complete -o filenames -o bashdefault -F _gadgetctl gadgetctl
""",
    ]
    return "\n".join(lines)


def zsh_script(info: CommandInfo) -> str:
    subs, opts, choices, value_opts = _tables(info)
    dyn_opts, dyn_args = _dynamic_tables(info)
    pairs = lambda table: [f"  {_quote(k)} {_quote(v)}" for k, v in table.items()]  # noqa: E731
    lines = [
        "#compdef gadgetctl",
        "# zsh completion for gadgetctl (generated by `make completions`; do not edit)",
        "typeset -gA _gadgetctl_subs _gadgetctl_opts _gadgetctl_choices _gadgetctl_valueopts",
        "typeset -gA _gadgetctl_dynopts _gadgetctl_dynargs",
        "_gadgetctl_subs=(",
        *pairs(subs),
        ")",
        "_gadgetctl_opts=(",
        *pairs(opts),
        ")",
        "_gadgetctl_choices=(",
        *pairs(dict(sorted(choices.items()))),
        ")",
        "_gadgetctl_valueopts=(",
        *[f"  {_quote(k)} 1" for k in sorted(value_opts)],
        ")",
        "_gadgetctl_dynopts=(",
        *pairs(dict(sorted(dyn_opts.items()))),
        ")",
        "_gadgetctl_dynargs=(",
        *pairs(dict(sorted(dyn_args.items()))),
        ")",
        r"""
# Candidates of KIND from `gadgetctl __complete KIND WORDS...` (the words before the cursor),
# shown with their descriptions.
_gadgetctl_dynamic() {
  local -a lines names shown
  local line
  lines=("${(@f)$(${${(Q)words[1]}/#\~/$HOME} __complete $1 "${(@)words[2,CURRENT-1]}" 2>/dev/null)}")
  for line in $lines; do
    [[ -z $line ]] && continue
    names+=("${line%%$'\t'*}")
    if [[ $line == *$'\t'* ]]; then shown+=("${line%%$'\t'*}  -- ${line#*$'\t'}"); else shown+=("$line"); fi
  done
  (( $#names )) && compadd -l -d shown -a names
}

_gadgetctl() {
  # `cmd`, not `path`: zsh ties $path to $PATH
  local cmd=. w i prev=${words[CURRENT-1]} cur=${words[CURRENT]} skip= npos=0
  local -a dyn
  for (( i = 2; i < CURRENT; i++ )); do
    w=${words[i]}
    if [[ -n $skip ]]; then skip=; continue; fi
    if [[ $w == -* ]]; then
      if [[ $w != *=* ]] && (( ${+_gadgetctl_valueopts[$cmd $w]} || ${+_gadgetctl_choices[$cmd $w]} )); then
        skip=1
      fi
      continue
    fi
    if [[ " ${_gadgetctl_subs[$cmd]} " == *" $w "* ]]; then
      if [[ $cmd == . ]]; then cmd=$w; else cmd="$cmd $w"; fi
    else
      (( npos++ ))
    fi
  done
  if (( ${+_gadgetctl_dynopts[$cmd $prev]} )); then _gadgetctl_dynamic ${_gadgetctl_dynopts[$cmd $prev]}; return; fi
  if (( ${+_gadgetctl_choices[$cmd $prev]} )); then compadd -- ${=_gadgetctl_choices[$cmd $prev]}; return; fi
  if (( ${+_gadgetctl_valueopts[$cmd $prev]} )); then _files; return; fi
  if [[ $cur == -* ]]; then compadd -- ${=_gadgetctl_opts[$cmd]}; return; fi
  if [[ -n ${_gadgetctl_subs[$cmd]} ]]; then compadd -- ${=_gadgetctl_subs[$cmd]}; return; fi
  if (( ${+_gadgetctl_dynargs[$cmd]} )); then
    dyn=(${=_gadgetctl_dynargs[$cmd]})
    if (( dyn[2] == 0 || npos < dyn[2] )); then
      _gadgetctl_dynamic $dyn[1]
      [[ $dyn[3] == files ]] && _files
      return
    fi
  fi
  _files
}
if [[ $zsh_eval_context[-1] == loadautofunc ]]; then _gadgetctl "$@"; else compdef _gadgetctl gadgetctl; fi
""",
    ]
    return "\n".join(lines)


FISH_FUNCTIONS = r"""
# Candidates of KIND (with descriptions) from `gadgetctl __complete KIND WORDS...`.
function __gadgetctl_candidates --argument-names kind
    set -l words (commandline -opc)
    set -l command (string replace -r '^~' $HOME -- $words[1])
    $command __complete $kind $words[2..-1] 2>/dev/null
end

# True while fewer than MAX positional words follow the DEPTH sub-command words (the
# values of the options given after MAX and DEPTH not counted).
function __gadgetctl_positionals_below --argument-names max depth
    set -l valueopts $argv[3..-1]
    set -l words (commandline -opc)
    set -l seen 0
    set -l count 0
    set -l skip 0
    for w in $words[2..-1]
        if test $skip = 1
            set skip 0
            continue
        end
        if string match -q -- '-*' $w
            if not string match -q -- '*=*' $w; and contains -- $w $valueopts
                set skip 1
            end
            continue
        end
        if test $seen -lt $depth
            set seen (math $seen + 1)
        else
            set count (math $count + 1)
        end
    end
    test $count -lt $max
end
"""


def fish_script(info: CommandInfo) -> str:
    lines = [
        "# fish completion for gadgetctl (generated by `make completions`; do not edit)",
        FISH_FUNCTIONS,
        "complete -c gadgetctl -f",
    ]
    for node in _walk(info):
        words = [] if node.path == ROOT else node.path.split(" ")
        cond = " ; and ".join(f"__fish_seen_subcommand_from {w}" for w in words)
        if node.subcommands:
            names = " ".join(node.subcommands)
            here = (cond + " ; and " if cond else "") + f"not __fish_seen_subcommand_from {names}"
            for name, sub in node.subcommands.items():
                lines.append(
                    f"complete -c gadgetctl -n {_quote(here)} -a {name} -d {_quote(sub.help)}"
                )
        elif words:
            lines += _fish_arguments(node, words, cond)
        for option in node.options:
            flags = []
            for name in option.names:
                flags.append(f"-l {name[2:]}" if name.startswith("--") else f"-s {name[1:]}")
            extra = " -r" if option.takes_value else ""
            kind = _dynamic_option(node.path, option)
            if kind:
                extra = f" -x -a {_quote(f'(__gadgetctl_candidates {kind})')}"
            elif option.choices:
                extra = f" -x -a {_quote(' '.join(option.choices))}"
            elif option.takes_value:
                extra = " -r -F"
            condition = f" -n {_quote(cond)}" if cond else " -n __fish_use_subcommand"
            lines.append(
                f"complete -c gadgetctl{condition} {' '.join(flags)}{extra} -d {_quote(option.help)}"
            )
    return "\n".join(lines) + "\n"


def _fish_arguments(node: CommandInfo, words: list[str], cond: str) -> list[str]:
    """Completion of a leaf command's positional words: files, dynamic candidates or both."""
    if node.path not in DYNAMIC_ARGUMENTS:
        return [f"complete -c gadgetctl -n {_quote(cond)} -F"]
    kind, count, files = DYNAMIC_ARGUMENTS[node.path]
    value_opts = " ".join(n for o in node.options if o.takes_value for n in o.names)
    below = f"__gadgetctl_positionals_below {count} {len(words)} {value_opts}".rstrip()
    dynamic_cond = cond if count == 0 else f"{cond} ; and {below}"
    lines = [
        f"complete -c gadgetctl -n {_quote(dynamic_cond)} -a {_quote(f'(__gadgetctl_candidates {kind})')}"
    ]
    if files:
        lines.append(f"complete -c gadgetctl -n {_quote(cond)} -F")
    elif count:
        lines.append(f"complete -c gadgetctl -n {_quote(f'{cond} ; and not {below}')} -F")
    return lines


def scripts() -> dict[str, str]:
    tree = command_tree()
    return {"bash": bash_script(tree), "zsh": zsh_script(tree), "fish": fish_script(tree)}


def write_all(directory: Path) -> list[Path]:
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for shell, text in scripts().items():
        target = directory / FILES[shell]
        target.write_text(text, encoding="utf-8")
        written.append(target)
    return written


if __name__ == "__main__":
    for path in write_all(Path(sys.argv[1] if len(sys.argv) > 1 else "completions")):
        print(path)
