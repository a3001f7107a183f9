"""Parameter declarations: the single source of truth for every parameter of the two units.

Each parameter is declared once, as a field of a frozen dataclass whose metadata holds a
:class:`ParameterSpec` (public name, unit, description, default, limits).  The C tables of the
model library (``fmu_src/rattle_model/rm_tables.c``), the FMUs' registration and
modelDescription, and the documentation tables are all generated from these declarations, so
they cannot drift apart.  The checks themselves (ranges, choices, the geometry's combination
checks) are the model library's: a parameter set is validated by the library when it is
constructed, with the library's message.

Values are plain SI floats (angles in rad, lengths in m).  Display units (deg, mm, um, rpm)
are metadata for the FMI layer only.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any

from . import library, units
from .interface import ANGLE_RANGE, SPEED_RANGE


@dataclass(frozen=True)
class ParameterSpec:
    """Declaration of one parameter.

    ``minimum``/``maximum`` are inclusive unless ``min_exclusive``/``max_exclusive``.
    ``choices`` maps the allowed integer codes of an enumeration parameter to their meaning,
    ``choice_names`` each code to the short identifier tools show for it (the item name of
    the FMI enumeration type): one name per code, unique.
    """

    name: str
    default: Any
    unit: str
    description: str
    minimum: float | None = None
    maximum: float | None = None
    min_exclusive: bool = False
    max_exclusive: bool = False
    display_unit: str | None = None
    choices: Mapping[int, str] | None = None
    choice_names: Mapping[int, str] | None = None

    def __post_init__(self) -> None:
        if self.choices is None:
            return
        names = self.choice_names or {}
        if sorted(names) != sorted(self.choices) or len(set(names.values())) != len(names) \
                or not all(re.fullmatch(r"[a-z][a-z0-9_]*", n) for n in names.values()):
            raise ValueError(f"parameter spec '{self.name}': choice_names {names!r} must name "
                             f"every code of {sorted(self.choices)} once, as identifiers "
                             "[a-z][a-z0-9_]*")

    @property
    def fmi_type(self) -> str:
        """FMI type name: ``Boolean``, ``Integer``, ``Real`` or ``String``."""
        if isinstance(self.default, str):
            return "String"
        if isinstance(self.default, bool):
            return "Boolean"
        if isinstance(self.default, int):
            return "Integer"
        return "Real"

    def allowed(self) -> str:
        """Human-readable statement of the allowed values, used in error messages."""
        if self.fmi_type == "Boolean":
            return "true or false"
        if self.fmi_type == "String":
            return "a string"
        if self.choices is not None:
            return "one of " + ", ".join(f"{k} ({v})" for k, v in self.choices.items())
        lo = "-inf" if self.minimum is None else _fmt(self.minimum)
        hi = "+inf" if self.maximum is None else _fmt(self.maximum)
        left = "(" if self.min_exclusive or self.minimum is None else "["
        right = ")" if self.max_exclusive or self.maximum is None else "]"
        unit = "" if self.unit in ("", "1") else f" {self.unit}"
        return f"{left}{lo}, {hi}{right}{unit}"

    def convert(self, value: Any) -> Any:
        """``value`` converted to the parameter's type, or ValueError naming it; the range is
        the model library's to check (:meth:`ParameterSet.__post_init__`)."""
        fmi_type = self.fmi_type
        if fmi_type == "String":
            if not isinstance(value, str):
                raise self._error(value, "must be a string")
            return value
        if fmi_type == "Boolean":
            if isinstance(value, bool) or value in (0, 1):
                return bool(value)
            raise self._error(value, "must be true or false")
        if fmi_type == "Integer":
            if isinstance(value, bool) or not _is_integral(value):
                raise self._error(value, "must be an integer")
            value = int(value)
            if not -(2**31) <= value < 2**31:
                raise self._error(value, "must be a 32-bit integer")
            return value
        if isinstance(value, bool):
            raise self._error(value, "must be a real number")
        try:
            return float(value)
        except (TypeError, ValueError, OverflowError):
            raise self._error(value, "must be a real number") from None

    def parse(self, text: str, label: str | None = None) -> Any:
        """The value a text gives the parameter (the VALUE of a command line's NAME=VALUE), by
        its declared type: a Real a decimal number; an Integer a whole number; an
        enumeration its code or its item name (``choice_names``, exactly as the
        modelDescription spells it: ``none``, not ``None``); a Boolean ``true`` or ``false``
        (any case) or ``1`` or ``0``; a String the text as it is, empty included.  Otherwise
        ValueError naming the parameter (as ``label``, default its name), the text and what is
        allowed.  The range is the model library's to check (:meth:`ParameterSet.__post_init__`)."""
        fmi_type = self.fmi_type
        if fmi_type == "String":
            return text
        word = text.strip()
        if fmi_type == "Boolean":
            if word.lower() in ("true", "false", "1", "0"):
                return word.lower() in ("true", "1")
            raise self._error(text, "is not a truth value", label, "true or false (or 1 or 0)")
        codes = {name: code for code, name in (self.choice_names or {}).items()}
        if word in codes:
            return codes[word]
        try:
            number = float(word)
        except ValueError:
            number = None
        if fmi_type == "Real":
            if number is None:
                raise self._error(text, "is not a number", label)
            return number
        if number is not None and _is_integral(number):
            return self.convert(number)
        if not codes:
            raise self._error(text, "is not a whole number", label)
        from difflib import get_close_matches

        near = get_close_matches(word, list(codes), n=1)
        guess = f" (did you mean '{near[0]}'?)" if near else ""
        raise self._error(text, f"is neither a code nor an item name of the enumeration{guess}",
                          label, ", ".join(f"{c} or '{n}'" for n, c in codes.items()))

    def _error(self, value: Any, reason: str = "is out of range", label: str | None = None,
               allowed: str | None = None) -> ValueError:
        return ValueError(
            f"parameter '{label or self.name}' = {value!r} {reason}; "
            f"allowed: {allowed or self.allowed()}"
        )


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def _is_integral(value: Any) -> bool:
    if isinstance(value, int):
        return True
    return isinstance(value, float) and math.isfinite(value) and value == int(value)


def declare(name: str, default: Any, unit: str, description: str, **limits: Any) -> Any:
    """Dataclass field carrying a :class:`ParameterSpec` in its metadata."""
    spec = ParameterSpec(name, default, unit, description, **limits)
    return field(default=default, metadata={"spec": spec})


def specs(cls_or_obj: Any) -> Iterator[tuple[str, ParameterSpec]]:
    """Yield ``(attribute, spec)`` for every declared parameter of a parameter dataclass."""
    for f in fields(cls_or_obj):
        spec = f.metadata.get("spec")
        if spec is not None:
            yield f.name, spec


class ParameterSet:
    """Mixin: values converted to their types and validated by the model library on
    construction (ranges, choices and the combination checks, with the library's message), and
    construction from public names."""

    #: The unit kind of the model library (``library.MESH`` or ``library.DRIVELINE``).
    KIND: int = -1

    def __post_init__(self) -> None:
        for attr, spec in specs(self):
            object.__setattr__(self, attr, spec.convert(getattr(self, attr)))
        units.check_parameters(self.KIND, self.to_public())

    @classmethod
    def from_public(cls, values: Mapping[str, Any]):
        """Build from a mapping of public (FMI) names to values; unknown names are an error."""
        by_name = {spec.name: attr for attr, spec in specs(cls)}
        unknown = sorted(set(values) - set(by_name))
        if unknown:
            raise ValueError(
                f"unknown parameter(s) {', '.join(unknown)}; known: {', '.join(sorted(by_name))}"
            )
        return cls(**{by_name[k]: v for k, v in values.items()})

    def to_public(self) -> dict[str, Any]:
        """Mapping of public (FMI) names to values."""
        return {spec.name: getattr(self, attr) for attr, spec in specs(self)}

    def with_public(self, **changes: Any):
        """Copy with some parameters changed, given by attribute name."""
        return replace(self, **changes)

    def derived(self) -> dict[str, float]:
        """Derived quantities of the parameter set, SI units (the model library's
        ``rm_describe``: the pair's geometry, the contact law, the wheel's normal mass, ...)."""
        return units.describe(self.KIND, self.to_public())


DEG = math.pi / 180.0

#: friction.form codes (see docs/model.md, eq. 12)
FRICTION_FORMS = {
    0: "load sharing: psi*A_e*tau_s + (1-psi)*A*eta*U/h",
    1: "apparent area: A*(psi*tau_s + (1-psi)*eta*U/h)",
    2: "as printed: A_e*(psi*tau_s + (1-psi)*eta*U/h)",
}
FRICTION_FORMS_NAMES = {0: "load_sharing", 1: "apparent_area", 2: "as_printed"}
#: contact.hertz_law codes
HERTZ_LAWS = {
    0: "exact elliptical Hertz contact (Johnson 1985, complete elliptic integrals)",
    1: "equivalent sphere of eq. 2, K = 4/3 E* (r_x r_y)^(1/4)",
}
HERTZ_LAWS_NAMES = {0: "exact_elliptical", 1: "equivalent_sphere"}
#: contact.geometry codes (docs/model.md section 2)
CONTACT_GEOMETRIES = {
    0: "crowned point contacts: each pair touches at the lowest point of its engaged contact "
       "line with its own crown offset (contact.crowning)",
    1: "the paper's: every pair in the zone of action an equivalent ellipsoid at the shared "
       "rigid approach (no crown), r_x and r_y (eq. 6) at the centre of its engaged contact "
       "line, K by contact.hertz_law",
    2: "unmodified flanks in line contact: every pair in the zone loaded along its engaged "
       "contact line, Palmgren's line-contact law",
}
CONTACT_GEOMETRIES_NAMES = {0: "crowned_points", 1: "paper_shared_approach",
                            2: "line_contact"}
#: contact.roughness codes (docs/model.md section 3)
ROUGHNESS_MODELS = {
    0: "smooth flanks",
    1: "Greenwood-Tripp asperity layer (surface.sigma, surface.gamma, "
       "surface.asperity_density) in series with the smooth law",
}
ROUGHNESS_MODELS_NAMES = {0: "smooth", 1: "greenwood_tripp"}
#: contact.dissipation codes
DISSIPATION_MODELS = {
    0: "none (the paper's equations: friction is the only loss)",
    1: "Hunt-Crossley, factor from contact.restitution at contact.restitution_speed",
    2: "Hunt-Crossley, factor contact.damping",
    3: "squeeze film (Stokes number): each impact's restitution e = contact.restitution_dry "
       "(1 - St_c/St), St = m v / (6 pi eta phi A_sq), realized exactly by a Hunt-Crossley "
       "factor set at its onset; no rebound (the approach speed is lost) for St <= St_c, the "
       "contact then damped by the pairs' squeeze films",
    4: "mesh damping ratio contact.damping_ratio: viscous, c = 2 zeta sqrt(k m) on the "
       "contact's linearized stiffness k = dW/d(delta) and the wheel's normal mass",
}
DISSIPATION_MODELS_NAMES = {0: "none", 1: "hunt_crossley_restitution", 2: "hunt_crossley_damping",
                            3: "squeeze_film", 4: "damping_ratio"}
#: tooth.compliance codes (docs/model.md section 3.7)
TOOTH_COMPLIANCES = {
    0: "none: rigid teeth, only the contact deforms (the paper's equations)",
    1: "bending, shear and compression of both teeth (Weber's energy method on the virtual "
       "spur teeth of the normal section) and of their gear bodies (Sainsot, Velex and "
       "Duverger 2004), per unit length of contact line, in series with each pair's contact "
       "law over the pair's engaged contact line",
}
TOOTH_COMPLIANCES_NAMES = {0: "none", 1: "weber_sainsot"}
#: friction.shear_speed codes
SHEAR_SPEEDS = {0: "entrainment speed u (paper eq. 12, 16)", 1: "sliding speed |v_s|"}
SHEAR_SPEEDS_NAMES = {0: "entrainment", 1: "sliding"}
#: vehicle.model codes (see docs/model.md section 6)
VEHICLE_MODELS = {
    0: "output shaft: spring-damper shaft.k, shaft.c to the reflected vehicle inertia vehicle.J "
       "with drag vehicle.drag + vehicle.drag_viscous*w",
    1: "constant load torque on the wheel, wheel.tau_load = vehicle.drag (the paper's M_res; "
       "the shaft, vehicle.J and vehicle.drag_viscous unused)",
}
VEHICLE_MODELS_NAMES = {0: "output_shaft", 1: "constant_load"}
#: lubricant.film codes
FILM_MODELS = {
    0: "eq. 11: the rigid gap plus the eq. 7 delta_max of the last impact (the paper)",
    1: "the larger of eq. 11 and the elastohydrodynamic central film of the loaded pair "
       "(Hamrock and Dowson 1977, fully flooded, isothermal, with lubricant.alpha)",
}
FILM_MODELS_NAMES = {0: "eq11_gap", 1: "ehl_central"}
#: friction.viscous_law codes
VISCOUS_LAWS = {
    0: "Newtonian, isoviscous: eta U / h (the paper)",
    1: "piezoviscous (Barus) eta = eta exp(alpha p) with a limiting shear stress: "
       "tau_L (1 - exp(-eta exp(alpha p) U / (h tau_L))), tau_L = tau_L0 + gamma_L p, "
       "p the pair's mean Hertz pressure",
}
VISCOUS_LAWS_NAMES = {0: "isoviscous", 1: "barus_limiting_shear"}


@dataclass(frozen=True)
class MeshParameters(ParameterSet):
    """Parameters of the gear-mesh impact and friction model (defaults: MODEL_NOTES section 3)."""

    # --- gear pair geometry -------------------------------------------------------------
    z_pinion: int = declare(
        "gear.z_pinion", 20, "1", "number of teeth of the pinion (input-shaft gear)",
        minimum=5, maximum=400)
    z_wheel: int = declare(
        "gear.z_wheel", 39, "1", "number of teeth of the wheel (output gear)",
        minimum=5, maximum=400)
    m_n: float = declare(
        "gear.m_n", 2.25e-3, "m", "normal module", minimum=1e-4,
        maximum=0.1, display_unit="mm")
    alpha_n: float = declare(
        "gear.alpha_n", 20.0 * DEG, "rad", "normal pressure angle",
        minimum=10.0 * DEG, maximum=35.0 * DEG, display_unit="deg")
    beta: float = declare(
        "gear.beta", 27.75 * DEG, "rad", "helix angle at the pitch cylinder (0 = spur)",
        minimum=0.0, maximum=45.0 * DEG, display_unit="deg")
    addendum: float = declare(
        "gear.h_a", 1.0, "1",
        "addendum coefficient: tip radius r_a = r + h_a m_n (1 = standard full depth, < 1 stub)",
        minimum=0.5, maximum=1.5)
    b: float = declare(
        "gear.b", 25e-3, "m", "face width in contact", minimum=1e-3,
        maximum=1.0, display_unit="mm")
    backlash: float = declare(
        "gear.backlash", 0.10e-3, "m",
        "total normal backlash (sum of both flank clearances along the tooth normal)",
        minimum=0.0, maximum=5e-3, display_unit="mm")
    # --- materials (pinion 1, wheel 2) ---------------------------------------------------
    E_pinion: float = declare(
        "material.E_pinion", 210e9, "Pa", "Young's modulus of the pinion",
        minimum=1e8, maximum=1e13)
    nu_pinion: float = declare(
        "material.nu_pinion", 0.30, "1", "Poisson's ratio of the pinion",
        minimum=0.0, maximum=0.5)
    E_wheel: float = declare(
        "material.E_wheel", 210e9, "Pa", "Young's modulus of the wheel",
        minimum=1e8, maximum=1e13)
    nu_wheel: float = declare(
        "material.nu_wheel", 0.30, "1", "Poisson's ratio of the wheel",
        minimum=0.0, maximum=0.5)
    density: float = declare(
        "material.rho", 7850.0, "kg/m3",
        "density of the tooth material (mass of the equivalent ellipsoid, eq. 7)",
        minimum=100.0, maximum=1e5)
    # --- wheel dynamics --------------------------------------------------------------------
    J_wheel: float = declare(
        "wheel.J", 1.3e-3, "kg.m2", "mass moment of inertia of the wheel (eq. 10, I_w)",
        minimum=1e-7, maximum=1e3)
    # --- Hertzian contact ------------------------------------------------------------------
    crowning: float = declare(
        "contact.crowning", 10e-6, "m",
        "composite lead crowning of the pair: separation of the flanks along the contact normal "
        "at the face ends relative to the face centre; every tooth pair touches at the lowest "
        "point of its engaged contact line with its own crown-drop offset, and the crown gives "
        "the flank radius along the contact line (eq. 6 read as crowning: "
        "r_y = b^2 / (8 C_b cos^2 beta_b)); used by contact.geometry = 0 (and as r_y of the "
        "asperity layer of contact.roughness = 1 there)",
        minimum=1e-6, maximum=1e-3, display_unit="um")
    hertz_law: int = declare(
        "contact.hertz_law", 0, "1", "load-approach law of each elliptical point contact "
        "(contact.geometry 0 and 1): "
        + "; ".join(f"{k} = {v}" for k, v in HERTZ_LAWS.items()),
        minimum=0, maximum=1, choices=HERTZ_LAWS,
        choice_names=HERTZ_LAWS_NAMES)
    contact_geometry: int = declare(
        "contact.geometry", 0, "1", "which tooth pairs carry load and how (docs/model.md "
        "section 2): " + "; ".join(f"{k} = {v}" for k, v in CONTACT_GEOMETRIES.items()),
        minimum=0, maximum=2, choices=CONTACT_GEOMETRIES,
        choice_names=CONTACT_GEOMETRIES_NAMES)
    roughness: int = declare(
        "contact.roughness", 0, "1", "load-approach law below a few surface.sigma (docs/model.md "
        "section 3): " + "; ".join(f"{k} = {v}" for k, v in ROUGHNESS_MODELS.items()),
        minimum=0, maximum=1, choices=ROUGHNESS_MODELS,
        choice_names=ROUGHNESS_MODELS_NAMES)
    asperity_density: float = declare(
        "surface.asperity_density", 1e9, "1/m2",
        "areal density of asperity summits of the flanks (Greenwood-Tripp, contact.roughness = "
        "1); default 1e9 m^-2 gives the roughness parameter density*gamma*sigma = 0.04 with the "
        "default surfaces (0.03-0.05 measured by Greenwood and Williamson 1966)",
        minimum=1e6, maximum=1e14)
    dissipation: int = declare(
        "contact.dissipation", 3, "1", "contact dissipation (default: the squeeze-film law of "
        "lubricated impacts, docs/model.md section 3.3): "
        + "; ".join(f"{k} = {v}" for k, v in DISSIPATION_MODELS.items()),
        minimum=0, maximum=4, choices=DISSIPATION_MODELS,
        choice_names=DISSIPATION_MODELS_NAMES)
    restitution: float = declare(
        "contact.restitution", 0.8, "1",
        "coefficient of restitution of a single lubricated tooth impact at "
        "contact.restitution_speed (contact.dissipation = 1); sets the Hunt-Crossley factor "
        "exactly, see docs/model.md section 3", minimum=0.01, maximum=1.0)
    restitution_speed: float = declare(
        "contact.restitution_speed", 4e-3, "m/s",
        "normal impact speed at which contact.restitution holds (default: the paper's typical "
        "impact velocity)", minimum=1e-5, maximum=10.0, display_unit="mm/s")
    damping: float = declare(
        "contact.damping", 0.0, "s/m",
        "Hunt-Crossley damping factor d in W = K*delta^1.5*(1 + d*delta_dot), used with "
        "contact.dissipation = 2", minimum=0.0, maximum=1e3)
    stokes_critical: float = declare(
        "contact.stokes_critical", 10.0, "1",
        "critical Stokes number St_c of the squeeze-film impact law (contact.dissipation = 3): "
        "no rebound below it (Gondret, Lance and Petit 2002; Joseph et al. 2001: about 10 for "
        "spheres in a liquid; docs/model.md section 3)", minimum=0.0, maximum=1e3)
    restitution_dry: float = declare(
        "contact.restitution_dry", 0.97, "1",
        "restitution of the unlubricated impact, the squeeze-film law's limit at large "
        "Stokes number (contact.dissipation = 3; steel on steel, Gondret et al. 2002)",
        minimum=0.01, maximum=1.0)
    squeeze_fraction: float = declare(
        "contact.squeeze_fraction", 0.03, "1",
        "film (starvation) parameter phi of the squeeze-film law (contact.dissipation = 3): "
        "the fraction of the flooded Reynolds squeeze-film force the flanks' oil film "
        "develops, 1 = flooded; with the critical Stokes number it sets the critical impact "
        "speed; no published value for a gear mesh: the default 0.03 is a calibration, its "
        "plausible range 0.01-0.1 (docs/model.md section 3.3)", minimum=1e-6, maximum=1.0)
    damping_ratio: float = declare(
        "contact.damping_ratio", 0.05, "1",
        "mesh damping ratio zeta (contact.dissipation = 4): viscous damping "
        "c = 2 zeta sqrt(k m_n) with k = dW/d(delta) the contact's linearized stiffness and m_n "
        "the wheel's normal mass (gear dynamics uses 0.03-0.1)", minimum=0.0, maximum=1.0)
    # --- the teeth's own compliance, in series with the contact ---------------------------
    tooth_compliance: int = declare(
        "tooth.compliance", 1, "1", "compliance of the teeth in series with each pair's "
        "contact law (docs/model.md section 3.7): "
        + "; ".join(f"{k} = {v}" for k, v in TOOTH_COMPLIANCES.items()),
        minimum=0, maximum=1, choices=TOOTH_COMPLIANCES,
        choice_names=TOOTH_COMPLIANCES_NAMES)
    body_ratio_pinion: float = declare(
        "tooth.body_ratio_pinion", 1.8, "1",
        "root-circle radius over bore radius of the pinion's body, where the body is held "
        "(h = r_f / r_int of the gear-body term of Sainsot, Velex and Duverger 2004, fitted for "
        "1.4-7; tooth.compliance = 1); default 1.8: the pinion's 22.6 mm root radius on a "
        "25 mm shaft", minimum=1.4, maximum=7.0)
    body_ratio_wheel: float = declare(
        "tooth.body_ratio_wheel", 2.7, "1",
        "root-circle radius over bore radius of the wheel's body (as "
        "tooth.body_ratio_pinion); default 2.7: the wheel's 46.8 mm root radius on a 35 mm "
        "shaft", minimum=1.4, maximum=7.0)
    # --- lubricant, surfaces, friction (eq. 11-17) ----------------------------------------
    friction_enabled: bool = declare(
        "friction.enabled", True, "", "include flank friction (eq. 12-17)")
    friction_form: int = declare(
        "friction.form", 0, "1", "reading of eq. 12 (see docs/model.md): "
        + "; ".join(f"{k} = {v}" for k, v in FRICTION_FORMS.items()),
        minimum=0, maximum=2, choices=FRICTION_FORMS,
        choice_names=FRICTION_FORMS_NAMES)
    shear_speed: int = declare(
        "friction.shear_speed", 0, "1", "speed in the viscous term eta*U/h: "
        + "; ".join(f"{k} = {v}" for k, v in SHEAR_SPEEDS.items()),
        minimum=0, maximum=1, choices=SHEAR_SPEEDS,
        choice_names=SHEAR_SPEEDS_NAMES)
    viscous_law: int = declare(
        "friction.viscous_law", 0, "1", "shear stress of the film in the viscous term: "
        + "; ".join(f"{k} = {v}" for k, v in VISCOUS_LAWS.items()),
        minimum=0, maximum=1, choices=VISCOUS_LAWS,
        choice_names=VISCOUS_LAWS_NAMES)
    tau_s: float = declare(
        "friction.tau_s", 2.28e8, "Pa",
        "boundary shear strength of the asperity junctions (default gives a boundary "
        "friction coefficient A_e*tau_s/W = 0.1 with the default surfaces)",
        minimum=0.0, maximum=1e10)
    eta: float = declare(
        "lubricant.eta", 0.05, "Pa.s", "dynamic viscosity of the lubricant",
        minimum=1e-5, maximum=1e3)
    alpha_pv: float = declare(
        "lubricant.alpha", 2e-8, "1/Pa",
        "pressure-viscosity coefficient of Barus' law eta(p) = eta exp(alpha p) "
        "(friction.viscous_law = 1; mineral gear oils about 1.5e-8 to 2.5e-8 1/Pa at 40-60 C)",
        minimum=0.0, maximum=1e-7)
    tau_limit_0: float = declare(
        "lubricant.tau_limit_0", 2e6, "Pa",
        "limiting shear stress of the lubricant at ambient pressure, tau_L0 in "
        "tau_L = tau_L0 + gamma_L p (friction.viscous_law = 1; Bair and Winer 1979)",
        minimum=1e3, maximum=1e12)
    tau_limit_slope: float = declare(
        "lubricant.tau_limit_slope", 0.07, "1",
        "pressure coefficient gamma_L of the limiting shear stress, tau_L = tau_L0 + gamma_L p "
        "(friction.viscous_law = 1; about 0.03-0.1 for mineral oils)",
        minimum=0.0, maximum=1.0)
    film: int = declare(
        "lubricant.film", 0, "1", "film thickness h of the film parameter lambda = h/sigma: "
        + "; ".join(f"{k} = {v}" for k, v in FILM_MODELS.items()),
        minimum=0, maximum=1, choices=FILM_MODELS,
        choice_names=FILM_MODELS_NAMES)
    sigma: float = declare(
        "surface.sigma", 0.4e-6, "m", "composite RMS roughness of the flanks",
        minimum=1e-9, maximum=1e-3, display_unit="um")
    gamma: float = declare(
        "surface.gamma", 1e-4, "m", "average asperity tip radius (eq. 13)",
        minimum=1e-7, maximum=1.0, display_unit="um")
    # --- outputs --------------------------------------------------------------------------
    rattle_time: float = declare(
        "rattle.time_constant", 1.0, "s",
        "time constant of the rattle index: the impact kinetic energy per second, exponentially "
        "averaged like a sound level meter's time weighting (1 s = 'slow')",
        minimum=1e-3, maximum=1e4)
    # --- initial state -------------------------------------------------------------------
    phi_start: float = declare(
        "wheel.phi_start", 0.0, "rad",
        "initial wheel angle (used when init.in_contact is false)", display_unit="deg",
        **ANGLE_RANGE)
    w_start: float = declare(
        "wheel.w_start", 0.0, "rad/s",
        "initial wheel speed (used when init.in_contact is false)", display_unit="rpm",
        **SPEED_RANGE)
    init_in_contact: bool = declare(
        "init.in_contact", True, "",
        "start in the static flank equilibrium for the initial load torque and pinion "
        "speed (no start-up transient); false = start from wheel.phi_start, wheel.w_start")
    # --- numerics ------------------------------------------------------------------------
    h_max: float = declare(
        "solver.h_max", 1e-5, "s",
        "largest integration substep while teeth are in contact (free flight is exact)",
        minimum=1e-8, maximum=1e-2)
    h_comm_max: float = declare(
        "solver.h_comm_max", 1.0, "s",
        "largest communication step accepted: a guard against absurd steps (a step costs "
        "h/solver.h_max substeps in contact), not an accuracy limit; the coupling's accuracy "
        "against the step is in docs/tools.md",
        minimum=1e-7, maximum=1.0)

    # --- how the unit reads its inputs (docs/tools.md: held inputs, first step) -------------
    settle_first_step: bool = declare(
        "init.settle_first_step", True, "",
        "when the pinion inputs or wheel.tau_load of the first doStep differ from those at the "
        "end of initialization (a master that exchanges no values during initialization), "
        "first settle the wheel in the static flank equilibrium for them, as init.in_contact "
        "does at initialization (only with init.in_contact); false = step from the "
        "initialized wheel state")
    continue_when_held: bool = declare(
        "inputs.continue_when_held", True, "",
        "when the master holds pinion.phi, pinion.w, pinion.a (set none of them since the "
        "last step, or set the last step's values again; e.g. fmpy simulate of this FMU "
        "alone), the pinion runs on at constant "
        "speed from where the last step left it (at the first step: from pinion.phi at "
        "pinion.w; pinion.a unused); false = take held values literally (the pinion jumps "
        "back to the held angle at every step)")

    KIND = library.MESH


RPM = 2.0 * math.pi / 60.0
#: Number of engine-order slots of the input-shaft kinematics.
N_ORDERS = 4


def _order(k: int, default: float):
    return declare(f"engine.order[{k}]", default, "1",
                   f"engine order number of fluctuation slot {k} (cycles per revolution)",
                   minimum=0.1, maximum=100.0)


def _amplitude(k: int, default: float):
    return declare(f"engine.amplitude[{k}]", default, "rad/s2",
                   f"angular-acceleration amplitude of engine-order slot {k} (0 = off)",
                   minimum=0.0, maximum=1e6)


def _phase(k: int):
    return declare(f"engine.phase[{k}]", 0.0, "rad",
                   f"phase of the acceleration cosine of engine-order slot {k}",
                   minimum=-2.0 * math.pi, maximum=2.0 * math.pi, display_unit="deg")


@dataclass(frozen=True)
class DrivelineParameters(ParameterSet):
    """Parameters of the driveline (defaults: MODEL_NOTES section 3, creep rattle)."""

    # --- input shaft kinematics ---------------------------------------------------------
    w_mean: float = declare(
        "engine.w_mean", 830.0 * RPM, "rad/s", "mean input-shaft (engine) speed",
        minimum=1.0, maximum=2000.0, display_unit="rpm")
    # Engine orders: up to N_ORDERS slots; a slot with zero amplitude is off.
    order_1: float = _order(1, 2.0)
    amplitude_1: float = _amplitude(1, 300.0)
    phase_1: float = _phase(1)
    order_2: float = _order(2, 4.0)
    amplitude_2: float = _amplitude(2, 200.0)
    phase_2: float = _phase(2)
    order_3: float = _order(3, 6.0)
    amplitude_3: float = _amplitude(3, 150.0)
    phase_3: float = _phase(3)
    order_4: float = _order(4, 8.0)
    amplitude_4: float = _amplitude(4, 0.0)
    phase_4: float = _phase(4)
    phi_start: float = declare(
        "pinion.phi_start", 0.0, "rad", "input-shaft angle at the start time",
        display_unit="deg", **ANGLE_RANGE)
    a_over_step: bool = declare(
        "pinion.a_over_step", True, "",
        "output as pinion.a the mean acceleration over the coming step, (w(t+h) - w(t))/h with "
        "h the last communication step, so that the mesh's Taylor polynomial of the pinion "
        "keeps the pinion speed continuous from step to step; false = the instantaneous "
        "acceleration (its speed error at the step end, jerk*h^2/2, then jumps at every "
        "communication point)")
    speed_table: str = declare(
        "engine.speed_table", "", "",
        "CSV file of measured input-shaft speed (columns: time [s], speed [rad/s]; header "
        "optional); relative paths resolve against the FMU resources; empty = engine orders")
    # --- output shaft and vehicle --------------------------------------------------------
    k_shaft: float = declare(
        "shaft.k", 0.2, "N.m/rad",
        "torsional stiffness of the output shaft (default: a very soft coupling, so that the "
        "wheel sees the nearly constant drag of the paper's M_res; see docs/model.md section 6)",
        minimum=1e-3, maximum=1e9)
    c_shaft: float = declare(
        "shaft.c", 0.005, "N.m.s/rad",
        "torsional damping of the output shaft (default light: see docs/model.md section 6)",
        minimum=0.0, maximum=1e6)
    J_vehicle: float = declare(
        "vehicle.J", 5.0, "kg.m2", "vehicle inertia reflected to the output shaft",
        minimum=1e-6, maximum=1e6)
    drag: float = declare(
        "vehicle.drag", 0.0833, "N.m",
        "constant drag torque on the vehicle side (creep load; default 0.5 M*, half the load "
        "the default engine orders can separate the default wheel from, M* = wheel.J "
        "z_p/z_w 250 rad/s^2 = 0.1667 N.m; see docs/model.md section 6)",
        minimum=-1e5, maximum=1e5)
    drag_viscous: float = declare(
        "vehicle.drag_viscous", 0.0, "N.m.s/rad", "speed-proportional drag coefficient",
        minimum=0.0, maximum=1e5)
    vehicle_model: int = declare(
        "vehicle.model", 0, "1", "what loads the wheel: "
        + "; ".join(f"{k} = {v}" for k, v in VEHICLE_MODELS.items()),
        minimum=0, maximum=1, choices=VEHICLE_MODELS,
        choice_names=VEHICLE_MODELS_NAMES)
    h_max: float = declare(
        "solver.h_max", 1e-4, "s", "largest integration substep of the output shaft",
        minimum=1e-8, maximum=1.0)
    h_comm_max: float = declare(
        "solver.h_comm_max", 1.0, "s",
        "largest communication step accepted: a guard against absurd steps (a step costs "
        "h/solver.h_max substeps), not an accuracy limit; the wheel is extrapolated linearly "
        "over a step, accuracy against the step in docs/tools.md",
        minimum=1e-7, maximum=1.0)

    # --- how the unit reads its inputs (docs/tools.md: held inputs, first step) -------------
    settle_first_step: bool = declare(
        "init.settle_first_step", True, "",
        "when wheel.phi or wheel.w of the first doStep differ from those at the end of "
        "initialization (a master that exchanges no values during initialization), first "
        "start the output shaft anew in steady state behind them, as at initialization; "
        "false = step from the initialized shaft")
    continue_when_held: bool = declare(
        "inputs.continue_when_held", True, "",
        "when the master holds wheel.phi and wheel.w (set neither since the last step, or "
        "set the last step's values again; e.g. fmpy simulate of this FMU alone), the wheel "
        "runs on at constant speed "
        "from where the last step left it (at the first step: from wheel.phi at wheel.w); "
        "false = take held values literally (the wheel jumps back to the held angle at every "
        "step)")

    KIND = library.DRIVELINE

    def order_terms(self) -> list[tuple[float, float, float]]:
        """``(order, amplitude [rad/s^2], phase [rad])`` of the active engine orders."""
        return [
            (getattr(self, f"order_{k}"), getattr(self, f"amplitude_{k}"),
             getattr(self, f"phase_{k}"))
            for k in range(1, N_ORDERS + 1)
            if getattr(self, f"amplitude_{k}") != 0.0
        ]
