"""Effects at a bolted joint (places of kind ``"joint"``): micro-slip friction (an Iwan model
of Jenkins elements) and cubic stiffness. The clearance and damping effects fit joints too
(:mod:`.contact`, :mod:`.elements`).

A joint's interface stays closed under the bolts' preload; what changes with amplitude is its
tangential behaviour. Micro-slip (Segalman 2005; Brake 2018, Ch. 2 and 10): the interface's
edges slip while its centre sticks, so the joint softens and dissipates more as the load
grows, until the whole interface slips at the macro-slip force ``mu x preload``. An Iwan
model (Iwan 1966) represents it as Jenkins elements in parallel: each a spring ``k_i`` in
series with a Coulomb slider of slip force ``F_i``.
"""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal

import numpy as np
from pydantic import Field

from ..errors import SensfwError
from ..options import Float, Int
from ..params import MM, Parameter
from ..plugins import effects
from .base import Effect, add_spring_along_normal, decade_probes
from .laws import WithCubic, WithResidual, tangential_stiffness


@effects.register("micro_slip")
class MicroSlip(Effect):
    """Micro-slip friction at a joint: a discrete Iwan model of Jenkins elements in parallel
    with what remains of the joint's own law, along the joint's tangent, at each of its
    interface point pairs (``place.points``; its one pair ``r0``/``r1`` otherwise), sharing
    the parameters equally among them as the joint shares its law.

    The joint's stiffness (its law's ``k_t`` at zero slip: the stuck interface, what a linear
    model calibrates at a low level) is split: ``microslip_residual`` of it stays in the
    joint's law (the interface's part that never slips: the bolts' shanks, the centre under
    the heads), the rest goes into the Jenkins elements, which lose it as they slip. So the
    effect changes nothing where the interface sticks, and a fully slipped joint keeps
    ``microslip_residual`` of its stiffness (Segalman's four-parameter Iwan model with a
    residual stiffness; Brake 2018, Ch. 10). ``microslip_residual = 1`` is the joint without
    the effect.

    Each Jenkins element is a spring ``k_i`` in series with a Coulomb slider of slip force
    ``F_i`` between the two beams' points along the tangent (``hooks.add_jenkins``: the
    model integrates the slider's position by return mapping, exact Coulomb friction with
    no regularisation; the elements start stuck at the static state); per point
    ``elements`` of them (an option, default 3) with equal springs. Their slip
    displacements ``phi_i = F_i / k_i`` follow a power-law density ``phi^chi`` on ``[0,
    phi_max]`` (Segalman 2005; ``chi = microslip_exponent``, the elements are its
    quantiles: ``chi < 0`` puts more of them at small slips, ``chi > 0`` near
    ``phi_max``), scaled so that all the forces add up to
    ``microslip_force``, the force at which the whole interface slips (friction coefficient
    x bolt preload). ``spacing = "log"`` (an option) discretises the same density
    differently: the elements' slip displacements are log-spaced over ``decades`` decades
    below ``phi_max`` (the lowest bin takes the tail below), each element with the stiffness
    of its bin's share of the density and the bin's force-preserving mean slip (``int phi
    rho / int rho``), so the total stiffness and the macro-slip force are the density's
    exactly, and the low-force tail that equal-stiffness quantiles leave to one element
    (chi = -0.9, 6 quantiles, a macro-slip force of 530 N: slip forces 2e-8, 1e-3, 0.2, 5,
    60 and 460 N summed over the points) gets one element per ``decades / elements``
    decades (on the UNESP-BERT records, 8 log-spaced elements fitted no better than 6
    quantiles: README). Where bending makes the interface slip most, the elements slip
    first: the joint softens from low levels on and more as the load grows, and dissipates
    (Masing's rule: a stuck element is lossless, a slipping one dissipates ``4 F_i (a -
    phi_i)`` per cycle of slip amplitude ``a``).
    """

    name = "micro_slip"
    fits = ("joint",)
    needs = ("add_jenkins",)
    signatures = ("resonances move down as the level rises", "damping grows with level",
                  "odd harmonics")
    signature_classes = frozenset({"softening"})
    #: the joint keeps all its stiffness: no elements
    neutral: ClassVar[dict[str, float]] = {"microslip_residual": 1.0}

    class Options(Effect.Options):
        elements: Annotated[Int, Field(ge=1, le=64)] = Field(
            3, description="Jenkins elements per interface point, an integer in 1-64: "
                           "quantiles of the slip density (3 resolve its middle; a "
                           "density whose low-force tail matters, as on records far "
                           "apart in level, needs more)")
        spacing: Literal["quantile", "log"] = Field(
            "quantile", description="how the elements discretise the slip density: "
                                    "'quantile' (equal springs at its quantiles) or 'log' "
                                    "(log-spaced slips over `decades`, springs weighted by "
                                    "the density)")
        decades: Annotated[Float, Field(gt=0.0, le=12.0)] = Field(
            4.0, description="with spacing = 'log': the decades of slip below the largest "
                             "that the elements resolve, a number in (0, 12]")

    def __init__(self, attach: str | None = None, elements: int = 3,
                 spacing: str = "quantile", decades: float = 4.0):
        super().__init__(attach)
        self.elements = int(elements)
        self.spacing = spacing
        self.decades = float(decades)

    def spec(self) -> dict:
        extra = {} if self.elements == 3 else {"elements": self.elements}
        if self.spacing != "quantile":
            extra.update(spacing=self.spacing, decades=self.decades)
        return {**super().spec(), **extra}

    def parameters(self):
        # ranges from the UNESP-BERT beam: two M6 bolts at 5 Nm (~4 kN preload each) with
        # mu 0.2-0.6 slip at 1.6-5 kN, and the range leaves a decade on either side; the
        # linear model at 0.30 V wants the joint ~50x softer than at 0.05 V
        return [Parameter("microslip_residual", "", 0.1, 0.001, 1.0,
                          "fraction of the joint's tangential stiffness left when its "
                          "interface slips completely (1: no micro-slip)",
                          "Effect: micro_slip"),
                Parameter("microslip_force", "N", 2000.0, 20.0, 20000.0,
                          "force at which the whole interface slips (friction coefficient "
                          "x bolt preload)", "Effect: micro_slip"),
                Parameter("microslip_exponent", "", -0.5, -0.9, 2.0,
                          "exponent chi of the slip-displacement density phi^chi (Segalman)",
                          "Effect: micro_slip")]

    def jenkins(self, p, stiffness: float, points: int = 1) -> list[tuple[float, float]]:
        """``(k_i, F_i)`` (N/m, N) of the elements at one of ``points`` interface points of a
        joint whose tangential stiffness is ``stiffness`` (N/m)."""
        n = self.elements
        k_all = (1.0 - p["microslip_residual"]) * stiffness / points
        a = 1.0 + p["microslip_exponent"]
        if self.spacing == "quantile":
            k = np.full(n, k_all / n)
            phi = ((np.arange(n) + 0.5) / n) ** (1.0 / a)
        else:  # log-spaced bins of the density phi^chi on [0, 1], the tail in the first
            edges = np.concatenate([[0.0], 10.0 ** (-self.decades * (1.0 - np.arange(1, n + 1)
                                                                      / n))])
            mass = np.diff(edges ** a)  # int phi^chi, up to the common factor 1 / a
            k = k_all * mass / mass.sum()
            phi = a / (a + 1.0) * np.diff(edges ** (a + 1.0)) / mass
        force = k * phi * (p["microslip_force"] / points) / float(np.sum(k * phi))
        return [(float(ki), float(fi)) for ki, fi in zip(k, force, strict=True)]

    def probes(self, comparisons):
        """The macro-slip force at 200 N, 2 kN and 20 kN with a tenth of the joint's
        stiffness left (the elements slip at the measured levels at the lower forces and
        stick at the higher), the rest nominal."""
        return decade_probes(self, "microslip_force")

    def apply(self, place, hooks, p):
        if p["microslip_residual"] >= 1.0:  # neutral: the joint's own law, untouched
            return
        law = hooks.contact_law(place.name)
        stiffness = tangential_stiffness(law)
        if not stiffness > 0:
            raise SensfwError(f"micro_slip at {place.name!r}: the joint's law has no "
                              f"tangential stiffness to split ({stiffness:g} N/m)")
        hooks.set_contact_law(place.name, WithResidual(law, p["microslip_residual"]))
        pairs = place.points or ((place.r0, place.r1),)
        for j, (r0, r1) in enumerate(pairs):
            for i, (k, force) in enumerate(self.jenkins(p, stiffness, len(pairs))):
                hooks.add_jenkins(f"jenkins{j + 1}.{i + 1}@{place.name}", place.body0, r0,
                                  place.body1, r1, place.tangent, k, force)


@effects.register("cubic_stiffness")
class CubicStiffness(Effect):
    """A hardening stiffness, the Duffing oscillator's ``-k3 e^3`` (Worden & Tomlinson
    2001; Kerschen et al. 2006). At a joint, a cubic term in its slip law, ``F = F_base(s) -
    k3 s^3``: the interface stiffens as it slips further (bolt shank bearing on its hole,
    asperities flattening). At a body, a spring cubic in the displacement of the body point
    from where it rests, along the place's normal: a contact the motion closes from zero
    load, with no preload to linearise it (a part seated without play or preload, a ball
    between two plates; two-sided, so no even harmonics). Either way the resonances it takes
    part in move up with level, with no shift at small amplitude."""

    name = "cubic_stiffness"
    fits = ("joint", "body")
    signatures = ("resonances move up as the level rises", "odd harmonics")
    signature_classes = frozenset({"hardening"})
    neutral: ClassVar[dict[str, float]] = {"cubic_stiffness": 0.0}

    def parameters(self):
        # slips of 4-20 um at the UNESP-BERT levels: k3 s^2 ~ joint stiffness at 1e9; the
        # shaft model's bodies move 0.06-0.2 um at 0.03-0.1 N: 3e10 lifts the crankshaft
        # rocking mode 0.1 % at 0.03 N and 0.9 % at 0.1 N (tests/measure/test_signatures.py)
        return [Parameter("cubic_stiffness", "N/mm^3", 1.0e8, 0.0, 1.0e12,
                          "cubic coefficient of the joint's slip law or of the spring "
                          "at a body", "Effect: "
                          "cubic_stiffness")]

    def probes(self, comparisons):
        """The cubic coefficient at 1e8, 1e10 and 1e12 N/mm^3 (a joint's slip of microns
        wants the low end, a body point moving a tenth of a micron the high end)."""
        return decade_probes(self, "cubic_stiffness", (1e-4, 1e-2, 1.0))

    def apply(self, place, hooks, p):
        k3 = p["cubic_stiffness"] / MM**3
        if k3 <= 0:  # neutral: the joint's own law, untouched
            return
        if place.kind == "joint":
            hooks.set_contact_law(place.name, WithCubic(hooks.contact_law(place.name), k3))
            return
        add_spring_along_normal(hooks, place, f"cubic_stiffness@{place.name}",
                                lambda ops, e, e_dot: -k3 * e * e * e)
