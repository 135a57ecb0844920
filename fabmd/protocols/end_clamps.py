"""Coupons clamped at both ends along x: the clamp length and where the clamps are.

Shared by :class:`~fabmd.protocols.tension.Tension` and
:class:`~fabmd.protocols.bias_extension.BiasExtension`: both clamp ``clamp_length_m`` at
each end of the coupon (length along x) and move the clamps apart along x.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import InputError
from ..model.bead_model import BeadModel
from .driven import ClampedTest


@dataclass(frozen=True, kw_only=True)
class EndClampedTest(ClampedTest):
    """A coupon held by a clamp at each end along x.

    Args:
        clamp_length_m: clamped length at each end [m]; default 10 % of the coupon.
    """

    clamp_length_m: float | None = None

    def check_fields(self) -> None:
        self.check_positive_or_none("clamp_length_m")

    def default_clamp_length_m(self, model: BeadModel, length_m: float) -> float:
        """Clamp length when ``clamp_length_m`` is None: 10 % of the coupon [m]."""
        return 0.1 * length_m

    def clamps(self, model: BeadModel) -> tuple[float, float, float]:
        """(x of the left clamp's inner edge, of the right one's, gauge length) [m].

        The gauge length is the free length between the innermost clamped beads.
        """
        x = model.positions[:, 0]
        length = float(x.max() - x.min())
        clamp = self.clamp_length_m if self.clamp_length_m is not None else \
            self.default_clamp_length_m(model, length)
        if 2 * clamp >= 0.8 * length:
            raise InputError(f"{self.protocol}.clamp_length_m = {clamp:g} m leaves no gauge "
                             f"length on a {length:g} m coupon; use at most {0.4 * length:g} m "
                             f"per end")
        left, right = self.clamp_edges(x, float(x.min() + clamp), float(x.max() - clamp))
        gauge = float(x[x > right].min() - x[x < left].max())
        return float(left), float(right), gauge
