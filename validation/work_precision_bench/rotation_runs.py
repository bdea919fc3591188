"""The rotation cases run: free_regular, free_separatrix, heavy_top, free_extended."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import mpmath
import rotation_cases

import cayley_heyoka as ch
from cayley_heyoka.reference import FreeRigidBody

from .cases import (
    EXTENDED_LEVELS,
    QUICK_RTOL,
    REFERENCE_TOL,
    ROTATION,
    RTOL,
    heavy_top_data,
    heavy_top_example,
    quad_tolerances,
    rotation_data,
    tolerances,
)
from .errors import closed_form_end, final_values, rotation_error
from .our_side import ours, reference_check, reference_run
from .peers import mpmath_point, scipy_sweep
from .records import Case


def _tuple(values: Sequence[Any]) -> str:
    return "(" + ", ".join(str(v) for v in values) + ")"


def free_body(name: str, key: str, periods: float, quick: bool) -> Case:
    rc = rotation_cases.BY_NAME[key]
    body = FreeRigidBody(rc.inertia, rc.rates, attitude=(1.0, 0.0, 0.0, 0.0), dps=30)
    t_end = float(periods * body.period)
    distance = rotation_cases.separatrix_distance(rc.inertia, rc.rates)
    case = Case(
        name,
        f"{rc.title[0].upper()}{rc.title[1:]} (validation/rotation_cases.py `{key}`): inertia "
        f"{rc.inertia}, rates "
        f"{tuple(round(x, 6) for x in rc.rates)}, identity attitude; "
        f"t = {t_end:.6g} ({periods:g} periods of the rates; separatrix distance "
        f"{mpmath.nstr(distance, 2)})",
        "max(|Δω|/|ω|, quaternion distance up to sign) at the final time",
        "the closed form (`FreeRigidBody`, 40 digits)",
    )
    ref = closed_form_end(rc.inertia, rc.rates, t_end, 40)

    def error(result: ch.Result) -> float:
        return rotation_error(final_values(result, ROTATION), ref)

    for k, formulation in enumerate(("quaternion", "rodrigues")):
        data = rotation_data(rc, formulation)
        ours(case, formulation, data, "double", tolerances(quick, "double"), t_end, error)
        ours(case, formulation, data, "quad", quad_tolerances(quick, k), t_end, error)
    data = rotation_data(rc, "quaternion")
    scipy_sweep(
        case, data, t_end, (3, 4), lambda y: rotation_error(y, ref), QUICK_RTOL if quick else RTOL
    )
    if name == "free_regular" and not quick:
        # Radau only to show the case is not stiff: an implicit method buys nothing here.
        scipy_sweep(
            case, data, t_end, (3, 4), lambda y: rotation_error(y, ref), (1e-6, 1e-9), "Radau"
        )
    return case


def heavy_top(quick: bool) -> Case:
    example = heavy_top_example()
    t_end = 5.0 if quick else 50.0
    case = Case(
        "heavy_top",
        f"examples/heavy_top.toml: inertia {_tuple(example['body']['inertia'])}, centre of "
        f"mass {_tuple(example['forces']['heavy_top']['center_of_mass'])}, weight "
        f"{example['forces']['heavy_top']['weight']}; identity attitude; t = {t_end:g}",
        "max(|Δω|/|ω|, quaternion distance up to sign) at the final time",
        f"our quaternion formulation in real128 at tolerance {REFERENCE_TOL}",
    )

    def data(formulation: str) -> dict:
        return heavy_top_data(example, formulation)

    ref_result = reference_run(data("quaternion"), t_end)
    ref = final_values(ref_result, ROTATION)

    def error(result: ch.Result) -> float:
        return rotation_error(final_values(result, ROTATION), ref)

    for k, formulation in enumerate(("quaternion", "rodrigues")):
        ours(
            case,
            formulation,
            data(formulation),
            "double",
            tolerances(quick, "double"),
            t_end,
            error,
        )
        ours(
            case,
            formulation,
            data(formulation),
            "quad",
            quad_tolerances(quick, k, reference=True),
            t_end,
            error,
        )
        if k > 0 and not quick:
            reference_check(case, formulation, data(formulation), t_end, error)
    scipy_sweep(
        case,
        data("quaternion"),
        t_end,
        (3, 4),
        lambda y: rotation_error(y, ref),
        QUICK_RTOL if quick else RTOL,
    )
    return case


def free_extended(quick: bool) -> Case:
    rc = rotation_cases.BY_NAME["generic"]
    t_end = 0.5 if quick else 5.0
    case = Case(
        "free_extended",
        f"The generic body of `free_regular` over t = {t_end:g}, in extended precision",
        "max(|Δω|/|ω|, quaternion distance up to sign) at the final time",
        "the closed form (`FreeRigidBody`, 100 digits)",
        levels=(1e-13, *EXTENDED_LEVELS, 1e-50, 1e-70),
    )
    ref = closed_form_end(rc.inertia, rc.rates, t_end, 100)

    def error(result: ch.Result) -> float:
        return rotation_error(final_values(result, ROTATION), ref)

    data = rotation_data(rc, "quaternion")
    for precision in ("double", "quad", "real113", "real256"):
        ours(case, "quaternion", data, precision, tolerances(quick, precision), t_end, error)
    if not quick:
        for dps, tols in ((34, (1e-12, 1e-20, None)), (77, (None,))):
            for tol_mp in tols:
                mpmath_point(case, rc, t_end, dps, tol_mp, ref)
    return case
