"""Options of the information set ``infoset``: the node set's, and (inherited) those of
the slab and point sections it may run instead (``sections``)."""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal

from kalman_vs_infoset.estim.intercept.slabs.options import SlabOptions
from pydantic import Field, model_validator


class InfosetOptions(SlabOptions):
    """Options of the information set: the node set's (``sections="nodes"``,
    :class:`~kalman_vs_infoset.estim.intercept.nodeset.estimator.NodeSetEstimator`) and,
    inherited, those of the slabs and point sections."""

    legacy_keys: ClassVar[dict[str, str]] = {
        k: k for k in ("n_sections", "sections", "kinematic_margin", "split_ratio")
    }

    sections: Annotated[
        Literal["nodes", "slabs", "points"],
        Field(
            description="nodes (exact slices, tight), slabs (guaranteed, coarse) or the "
            "seed's point sections (not guaranteed: silent between sections)"
        ),
    ] = "nodes"
    n_nodes: Annotated[
        int, Field(ge=4, le=200, description="nodes: nodes per piece after (re)gridding")
    ] = 12
    min_live_nodes: Annotated[
        int, Field(ge=4, le=200, description="nodes: a piece with fewer is re-gridded")
    ] = 5
    n_bands: Annotated[
        int | None,
        Field(
            ge=1, le=16, description="nodes: closing-speed bands (None: of 0.1 % each, at most 8)"
        ),
    ] = None
    max_pieces: Annotated[
        int,
        Field(
            ge=1,
            le=256,
            description="nodes: most pieces per closing-speed band (1: the kinematic term "
            "is sized over all ranges, and the set diverges near the target)",
        ),
    ] = 16
    node_split_ratio: Annotated[
        float, Field(gt=1.0, le=1e6, description="nodes: split a piece whose ranges span more")
    ] = 2.0
    min_split_tau_s: Annotated[
        float,
        Field(
            ge=0.0,
            le=1e4,
            description="nodes: count a piece's ratio of times to go from at least this, "
            "s (0: from the time to go at eps; a step or two saves the splits near "
            "the target, docs/performance.md)",
        ),
    ] = 0.0
    tighten_rtol: Annotated[
        float,
        Field(gt=0.0, le=1.0, description="nodes: refine where a bound exceeds the nodes by more"),
    ] = 0.01
    max_inserts: Annotated[
        int,
        Field(
            ge=0,
            le=256,
            description="nodes: rounds of node insertion after an update where a bound "
            "exceeds the nodes by more than tighten_rtol (times the live closing-speed "
            "bands over the initial ones)",
        ),
    ] = 16
    max_vertices: Annotated[
        int | None,
        Field(
            ge=8,
            le=100_000,
            description="nodes: outer-simplify a slice left with more vertices by a "
            "prediction (None: never; a cap voids the guarantee between nodes, "
            "docs/infoset.md)",
        ),
    ] = None
    split_bands: Annotated[
        bool,
        Field(description="nodes: split closing-speed bands where their width dominates"),
    ] = True
    # 32 left kp_fig5_range 1.058 times the exact width at 95 s (seed 103, random
    # errors, unguided); 64 gives 1.033, and guided engagements rarely reach either
    max_bands: Annotated[
        int, Field(ge=1, le=256, description="nodes: most live closing-speed bands")
    ] = 64
    # on by default: with it, guided sets stay within 1.03 of the exact width where the
    # per-band replay reached 1.03-1.05 (seeds 404, 425; docs/infoset.md); off is a speed
    # option (Fig. 5's bearings-only game runs about 1.7 times cheaper)
    impulse_per_piece: Annotated[
        bool,
        Field(
            description="nodes: replay each impulse over the node's own closing-speed "
            "band (a split band's halves lose the spread of earlier impulses too; false: "
            "over the band it was recorded in, cheaper and looser)"
        ),
    ] = True
    # auto: the extreme trials at each range update. Without them range-finder sets read
    # up to 1.043 of the exact width early in the approach (seeds 706, 720, 731); with
    # bearings only they cost 1.1-1.7x for no tightness need (docs/infoset.md)
    band_trials: Annotated[
        Literal["auto", "impulse_spread", "extreme_bands"],
        Field(
            description="nodes: which closing-speed bands a trial split tests: those the "
            "impulses may have spread (impulse_spread: a paying trial splits that band), "
            "or those and, every few seconds, the bands at the set's extremes of the miss "
            "(extreme_bands: a paying trial halves every live band); auto: the impulses' "
            "trials, and those at the extremes at every range measurement (no clock)"
        ),
    ] = "auto"

    @model_validator(mode="after")
    def _room_for_the_nodes(self) -> InfosetOptions:
        if self.min_live_nodes > self.n_nodes:
            raise ValueError(
                f"min_live_nodes ({self.min_live_nodes}) must be <= n_nodes ({self.n_nodes})"
            )
        return self

    def containment_margin_m(self, x_km: tuple[float, float], e_mps: float, dt_s: float) -> float:
        if self.sections != "points":
            return 0.0
        # the seed's point sections bracket the truth only above eps + one step + one
        # spacing; slabs and nodes contain it down to eps
        spacing_m = (x_km[1] - x_km[0]) * 1e3 / max(self.n_sections - 1, 1)
        return e_mps * dt_s + spacing_m

    def unused_fields(self) -> dict[str, str]:
        if self.sections == "nodes":
            why = 'the node set (sections = "nodes") does not read it: it sizes slabs and points'
            return {f: why for f in SlabOptions.model_fields if f != "kinematic_margin"}
        why = f'a node-set option: sections = "{self.sections}" does not read it'
        return {f: why for f in type(self).model_fields if f not in SlabOptions.model_fields
                and f != "sections"}  # fmt: skip

    def build(self, setting):
        if self.sections != "nodes":
            return self.slab_estimator(setting, sections=self.sections)
        from kalman_vs_infoset.estim.intercept.nodeset.estimator import NodeSetEstimator

        return NodeSetEstimator(
            setting.model,
            closing_speed_mps=setting.closing_speed_mps,
            n_bands=self.n_bands,
            n_nodes=self.n_nodes,
            min_live_nodes=self.min_live_nodes,
            kinematic_margin=self.kinematic_margin,
            split_ratio=self.node_split_ratio,
            min_split_tau_s=self.min_split_tau_s,
            max_pieces=self.max_pieces,
            tighten_rtol=self.tighten_rtol,
            max_inserts=self.max_inserts,
            max_vertices=self.max_vertices,
            split_bands=self.split_bands,
            max_bands=self.max_bands,
            impulse_per_piece=self.impulse_per_piece,
            band_trials=self.band_trials,
        )


#: the defaults (the node set's dataclass fields take theirs from here)
DEFAULTS = InfosetOptions()
