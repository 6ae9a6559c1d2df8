"""The settings of a push program (:class:`ProgramSettings`): the solver's options and the
two-stage scheme, each with its reason, and the rows' constants, which the row table
(``skeletons/rows.yaml``) declares; the measurements behind them are in
docs/experiments.md."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from functools import cache
from pathlib import Path

from robotplan.base.overlays import parse_overrides, read_overlays
from robotplan.base.resources import skeletons_dir
from robotplan.pushing.program.row_table import Param, row_parameters

__all__ = ["ARM_PROGRAM_SETTINGS", "DEFAULT_SETTINGS", "SCENE_CLASSES", "ProgramSettings",
           "RowParams", "load_overlays", "parse_program_overrides", "settings_for",
           "with_overrides"]


class RowParams:
    """One row's constants, read as attributes (``settings.row("goal").tol``)."""

    def __init__(self, row: str, values: dict[str, Param]) -> None:
        self._row, self._values = row, values

    def __getattr__(self, name: str) -> Param:
        try:
            return self.__dict__["_values"][name]
        except KeyError:
            raise AttributeError(f"row {self.__dict__['_row']!r} of skeletons/rows.yaml has "
                                 f"no parameter {name!r}") from None


def _table_rows() -> tuple[tuple[str, Param], ...]:
    return tuple(row_parameters().items())


@dataclass(frozen=True)
class ProgramSettings:
    guess_speed: float = 0.027  # m per step and axis in the initial guess (data: ≤ 2.9 cm)
    solver: str = "snopt"
    # hand SNOPT the per-step sparsity of the stepwise constraints. Off for free pushers (it
    # can turn a feasible kinematic stage infeasible); on for arms (the `arms` overlay),
    # whose dense rows over every joint are slow (docs/experiments.md#sparse-jacobians)
    sparse_jacobians: bool = False
    optimality_tol: float = 2e-3
    feasibility_tol: float = 1e-4
    # SNOPT major iterations of the learned stage (it starts from the kinematic plan and keeps
    # it when it ends worse): more cost time without better plans, fewer lose plans
    # (docs/experiments.md#learned-iterations)
    iterations: int = 30
    # the search stops at the first solved plan whose learned-dynamics residual (RMS per
    # step, mm) is at most this: F_flow's own one-step error in contact
    # (docs/experiments.md#dynamics-residual)
    good_rms_mm: float = 5.0
    # SNOPT's limit on minor (QP) iterations over a whole solve: this many per constraint
    # row, at least SNOPT's default 10,000 (docs/experiments.md#minor-iterations)
    minor_iterations_per_row: int = 12
    # warm start: first solve the kinematic program (sticking contact, pushing direction,
    # no H_F: milliseconds per iteration) and start the learned program from its solution
    warm_start: bool = True
    # False: the kinematic program is the plan, its quasi-static model in place of the
    # learned one: the analytic-model baseline of the paper's Fig. 6
    learned_stage: bool = True
    # with a given guess (a re-plan from an earlier plan), the kinematic stage starts from it
    warm_from_guess: bool = True
    # and the learned stage is not run when its start already meets every row with a
    # residual of at most good_rms_mm (docs/experiments.md#good-start)
    accept_good_start: bool = False
    # nor when its start misses the constraints by more than this (scaled violation; None:
    # always run) (docs/experiments.md#replan-learned-stage)
    learned_start_violation: float | None = None
    # a search's programs in request.workers processes where more than one is queued; off:
    # one after another in the searching process, for programs that only check their starts
    # (~0.06 s each against ~0.2 s to start the processes; docs/experiments.md#starts-first)
    parallel: bool = True
    warm_iterations: int = 300
    # the kinematic stage in chunks of this many major iterations, ending at the first chunk
    # that ends within warm_restart_above: a warm start needs the rows met, and SNOPT spends
    # the rest of warm_iterations on the costs (None: one solve;
    # docs/experiments.md#kinematic-chunks)
    warm_chunk: int | None = None
    # a kinematic solve that ends above this violation (but usable, ≤ WARM_USABLE) is solved
    # again from where it ended: it rescues SNOPT's "infeasibilities minimized" near a
    # solution (docs/experiments.md#warm-restart)
    warm_restart_above: float = 1e-3
    warm_restarts: int = 1
    # the paper's ablation (Fig. 11): off, the program has no H_coll (and no swept
    # clearance) between actor and object, or no H_PoC
    with_collision: bool = True
    with_contact: bool = True
    # the rows' constants as ("ROW.NAME", value) pairs, defaults from skeletons/rows.yaml
    rows: tuple[tuple[str, Param], ...] = field(default_factory=_table_rows)
    # a user's settings (``--program NAME=VALUE``) as (name, value) pairs: they win over
    # every scene class's overlay, also over those applied later (re-plans, routes)
    overrides: tuple[tuple[str, object], ...] = ()

    def row(self, name: str) -> RowParams:
        """The constants of the row ``name`` of the row table."""
        prefix = f"{name}."
        return RowParams(name, {k[len(prefix):]: v for k, v in self.rows
                                if k.startswith(prefix)})

    def value(self, name: str) -> object:
        """A setting by name: a field, or a row's constant ``ROW.NAME``."""
        return dict(self.rows)[name] if "." in name else getattr(self, name)

    def values(self) -> dict[str, object]:
        """Every setting by name (fields, then the rows' ``ROW.NAME``)."""
        plain = {f.name: getattr(self, f.name) for f in fields(self)
                 if f.name not in ("rows", "overrides")}
        return {**plain, **dict(self.rows)}

    def with_values(self, changes: Mapping[str, object]) -> ProgramSettings:
        """These settings with ``changes`` (fields, or rows' constants ``ROW.NAME``)."""
        plain = {k: v for k, v in changes.items() if "." not in k}
        dotted = {k: v for k, v in changes.items() if "." in k}
        unknown = set(dotted) - {k for k, _ in self.rows}
        if unknown:
            raise ValueError(f"not a row constant of skeletons/rows.yaml: {sorted(unknown)}")
        rows = tuple((k, dotted.get(k, v)) for k, v in self.rows)
        return replace(self, **plain, rows=rows) if dotted else replace(self, **plain)


DEFAULT_SETTINGS = ProgramSettings()  # the free pushers' settings
# the classes of the overlays (the re-plans' budget is a tier's: skeletons/tiers.yaml)
SCENE_CLASSES = ("arms", "routes", "pose", "rigid")


@cache
def load_overlays(path: Path | None = None) -> dict[str, dict]:
    """The overlays of ``skeletons/settings.yaml``, checked against the settings' names."""
    return read_overlays(path or skeletons_dir() / "settings.yaml", DEFAULT_SETTINGS.values(),
                         SCENE_CLASSES, "program setting")


def settings_for(*classes: str, base: ProgramSettings = DEFAULT_SETTINGS,
                 **changes: object) -> ProgramSettings:
    """``base`` with the overlays of the scene ``classes`` (``arms``, ``routes``) from
    ``skeletons/settings.yaml`` in order, then ``changes``, then the user's ``overrides``
    that ``base`` carries."""
    overlays, settings = load_overlays(), base
    for name in classes:
        settings = settings.with_values(overlays.get(name, {}))
    settings = settings.with_values(changes)
    return settings.with_values(dict(settings.overrides)) if settings.overrides else settings


def with_overrides(settings: ProgramSettings, overrides: Mapping[str, object] | None
                   ) -> ProgramSettings:
    """``settings`` with a user's ``overrides`` applied, and carried into every overlay
    applied after (:func:`settings_for`)."""
    if not overrides:
        return settings
    pairs = tuple(sorted(dict(overrides).items()))
    return replace(settings.with_values(dict(pairs)), overrides=pairs)


def parse_program_overrides(items: Sequence[str]) -> dict[str, object]:
    """``NAME=VALUE`` items (the CLI's ``--program``) as settings (fields, or rows'
    constants ``ROW.NAME``) with values of their types
    (:func:`robotplan.base.overlays.parse_overrides`)."""
    return parse_overrides(DEFAULT_SETTINGS.values(), items, "program setting")


ARM_PROGRAM_SETTINGS = settings_for("arms")
"""The program settings of scenes with arms."""
