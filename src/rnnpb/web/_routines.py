"""The routine level in the dashboard (``rnnpb serve --routines``, docs/routines.md): the
routine file learned over the running model version follows the interaction, and each step
message says the routine recognised and the movement expected next."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.errors import RnnpbError

log = logging.getLogger("rnnpb.web")


class RoutineLevel:
    """The routine files given (``files``) and, per model, the routine follower learned over
    it (a :class:`~rnnpb.model.routines.RoutineFollower`, or None) with a line on it. A routine
    file applies to the model it was learned over only, so a version made by teaching runs
    without one (and an Undo back to that model finds it again). Used on the session thread
    only."""

    def __init__(self, files: list[Path] | None = None) -> None:
        self.files = list(files or [])
        self._followers: dict[str, tuple[Any, str]] = {}  # fingerprint -> (follower, note)

    def follower(self, model, name: str | None) -> tuple[Any, str]:
        """The follower of ``model`` (offered as ``name``) and the line on it."""
        from rnnpb.model.routines import RoutineFollower, RoutineModel

        if model is None or not self.files:
            return None, ""
        known = self._followers.get(model.fingerprint)
        if known is not None:
            return known
        found: tuple[Any, str] = (
            None,
            f"no routine file was learned over {name} (given: "
            f"{', '.join(p.name for p in self.files)}, over other models)",
        )
        for path in self.files:
            try:
                routines = RoutineModel.load(path)
            except RnnpbError as error:  # checked when the server started; gone since
                log.warning("routine file %s: %s", path, error)
                continue
            if routines.lower_fingerprint == model.fingerprint:
                names = ", ".join(routines.routines)
                found = (RoutineFollower(routines), f"routines of {path.name}: {names}")
                break
        self._followers[model.fingerprint] = found
        return found

    def reset(self) -> None:
        """A new run: every follower forgets the interaction so far."""
        for follower, _ in self._followers.values():
            if follower is not None:
                follower.reset()

    def state(self, model) -> dict[str, Any]:
        """The ``routines`` part of the state message: whether a routine level runs, and a
        line on it (empty when the server was given no routine file)."""
        known = self._followers.get(model.fingerprint) if model is not None else None
        if known is None:  # made on the session thread when the model first steps or loads
            return {"on": False, "note": ""}
        return {"on": known[0] is not None, "note": known[1]}

    def step_fields(self, record, model, name: str | None) -> dict[str, Any]:
        """The step message's routine fields: the routine recognised (empty: none) and the
        movement it says comes next, with the steps left until then; no fields without a
        routine level for ``model``."""
        follower, _ = self.follower(model, name)
        if follower is None or model is None:
            return {}
        said = follower.observe(np.asarray(record.pb, dtype=np.float64))
        anticipated = ""
        if said.routine is not None:
            anticipated = model.nearest_pattern(said.predicted_pb)[0]
        steps_left = said.steps_left if said.routine is not None else None
        return {
            "routine": said.routine or "",
            "anticipated": anticipated,
            "switch_due": bool(said.switch_due),
            "steps_left": None if steps_left is None else round(float(steps_left), 1),
        }
