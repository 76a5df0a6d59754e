"""Guided root rotation theta(t): sympy expressions differentiated symbolically.

theta is a guided coordinate, so only its rate w = theta' and acceleration alpha = theta''
enter the equations of motion, as known inputs. The manoeuvre is generated as a kernel
(t, manoeuvre parameters) -> (theta, w, alpha) like every other kernel.
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

t = sp.Symbol("t", real=True)


@dataclass(frozen=True)
class ManeuverParam:
    name: str
    default: float
    unit: str
    description: str

    @property
    def symbol(self) -> sp.Symbol:
        return sp.Symbol(self.name, positive=True)


@dataclass(frozen=True)
class Maneuver:
    name: str
    params: tuple[ManeuverParam, ...]
    theta: sp.Expr
    description: str

    @property
    def rate(self) -> sp.Expr:
        return sp.diff(self.theta, t)

    @property
    def acceleration(self) -> sp.Expr:
        return sp.diff(self.theta, t, 2)

    @property
    def accelerates(self) -> bool:
        """False when theta'' vanishes identically: the alpha terms are then dropped."""
        return sp.simplify(self.acceleration) != 0


def _spin_up() -> Maneuver:
    ws = ManeuverParam("ws", 6.0, "rad/s", "final spin rate omega_s")
    ts = ManeuverParam("ts", 15.0, "s", "spin-up duration T_s")
    w, T = ws.symbol, ts.symbol
    ramp = (w / T) * (t**2 / 2 + (T / (2 * sp.pi))**2 * (sp.cos(2 * sp.pi * t / T) - 1))
    theta = sp.Piecewise((ramp, t <= T), (w * (t - T / 2), True))
    return Maneuver("spin_up", (ws, ts), theta,
                    "paper eq. (39): smooth spin-up to ws over ts, then constant speed")


def _constant() -> Maneuver:
    om = ManeuverParam("ws", 6.0, "rad/s", "constant spin rate")
    return Maneuver("constant", (om,), om.symbol * t, "constant spin rate from t = 0")


MANEUVERS: dict[str, Maneuver] = {m.name: m for m in (_spin_up(), _constant())}
