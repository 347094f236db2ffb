"""``bench delay``: the computation delay law (13) is proved to tolerate, plain and with the
delay-compensating prediction (``[controller] compensate_delay``), side by side on the same
designs in one run (docs/sampled-data.md, "Compensating a delay").

For each spec: its design at its rate; the largest delay the plain law's sampled-data check
proves (``largest_delay``, to 1/64 of the period) and the largest the predicted law's proves;
whether a one-period delay is certified by each; and the CPU time of one check of each, as
a ratio."""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import stt_codegen as stt
from stt_codegen.design.certificate.cascade_sampled import (cascade_class,
                                                            check_cascade_sampled,
                                                            largest_cascade_delay)
from stt_codegen.design.certificate.plant_class import plant_class
from stt_codegen.design.certificate.sampled import check_sampled_first_per_axis, largest_delay
from stt_codegen.design.samples import sample_tube
from stt_codegen.tube import reference

__all__ = ["DELAY_SPECS", "format_delay_report", "run_delay_bench"]

_TESTS = Path(__file__).resolve().parents[2] / "specs"
#: The bundled first-order and differential-drive cases, two cascades (the bundled
#: second-order-s1 and the test spec of the U-maze cascade at 400 Hz), and the test specs of
#: the Kobuki-like base and the first-order U-maze (all without their delay).
DELAY_SPECS = ("omnirobot-s1", "omnirobot-s2", "omnirobot-s3", "crossing-moving",
               "pointmaze-umaze", "office-base", "second-order-s1",
               str(_TESTS / "umaze-cascade-compensated.toml"),
               str(_TESTS / "kobuki-office.toml"), str(_TESTS / "umaze-first-order.toml"))


def _compared(spec, tube, plain: float | None, predicted: float | None, check) -> dict:
    """One row: the largest delays proved, whether a whole period is (``check(delay,
    compensate)`` runs one check and gives its verdict), and one check's CPU time of each
    law at the plain law's largest delay, as a ratio."""
    dt = 1.0 / tube.rate_hz
    whole = {compensate: check(dt, compensate) for compensate in (False, True)}
    seconds = {False: 0.0, True: 0.0}
    for compensate in (False, True):
        if plain:      # both checks pass there: each runs the whole horizon
            begin = time.process_time()
            check(plain, compensate)
            seconds[compensate] = time.process_time() - begin
    return {"spec": spec.name, "variant": spec.variant, "rate_hz": tube.rate_hz,
            "period_s": dt, "plain_delay_s": plain, "predicted_delay_s": predicted,
            "plain_whole_period": whole[False], "predicted_whole_period": whole[True],
            "check_cpu_ratio": seconds[True] / seconds[False] if seconds[False] > 0 else None}


def _cascade_row(spec, design) -> dict:
    """:func:`_row` of a second-order spec: the cascade's certificate of the design's own
    second stage, plain and predicted."""
    tube, stage = design.tube, design.stage
    plain = largest_cascade_delay(tube, spec, stage)
    predicted = largest_cascade_delay(tube, dataclasses.replace(spec, compensate_delay=True),
                                      stage)
    with reference.numpy_math():
        samples = sample_tube(tube)
    plants, start = cascade_class(spec), spec.second_order.initial_velocity
    return _compared(spec, tube, plain, predicted, lambda delay, compensate: (
        check_cascade_sampled(tube, samples, stage, plants, start, delay=delay,
                              compensate=compensate).passed))


def _row(source: str) -> dict:
    spec = stt.load_spec(source)
    spec = dataclasses.replace(spec, delay=0.0, jitter=0.0, compensate_delay=False)
    design = stt.design_tube(spec)
    if spec.variant == "cascade":
        return _cascade_row(spec, design)
    tube = design.tube
    predicted_spec = dataclasses.replace(spec, compensate_delay=True)
    with reference.numpy_math():
        samples, plants = sample_tube(tube), plant_class(spec)
        plain = largest_delay(tube, spec)
        predicted = largest_delay(tube, predicted_spec)
        # the plain check is defined up to dt - 2 jitter = dt: a whole period
        return _compared(spec, tube, plain, predicted, lambda delay, compensate: (
            check_sampled_first_per_axis(tube, samples, plants, delay=delay,
                                         compensate=compensate).passed))


def run_delay_bench(specs: tuple[str, ...] = DELAY_SPECS) -> dict:
    """The delay each law is proved to tolerate, per spec, in one run.

    Parameters
    ----------
    specs : tuple of str
        Bundled case names or spec paths (first-order, differential-drive or second-order).

    Returns
    -------
    dict
        ``rows``: one dict per spec (``plain_delay_s``, ``predicted_delay_s``, seconds or
        ``None`` when the check fails without delay; ``plain_whole_period``,
        ``predicted_whole_period``; ``check_cpu_ratio``, the predicted check's CPU time over
        the plain one's, both at the plain law's largest delay, where both pass).
    """
    return {"rows": [_row(source) for source in specs]}


def format_delay_report(report: dict) -> str:
    """The report as a table.

    Parameters
    ----------
    report : dict
        From :func:`run_delay_bench`.

    Returns
    -------
    str
    """
    def share(value, period):
        return "-" if value is None else f"{value * 1000:.4g} ms ({value / period:.0%})"

    lines = [f"{'spec':26} {'variant':11} {'rate':>7}  {'plain law':>17}  {'predicted':>17}"
             f"  {'one period: plain / predicted':>29}  {'check CPU':>9}"]
    for row in report["rows"]:
        period = row["period_s"]
        whole = (f"{'yes' if row['plain_whole_period'] else 'no'} / "
                 f"{'yes' if row['predicted_whole_period'] else 'no'}")
        ratio = "-" if row["check_cpu_ratio"] is None else f"{row['check_cpu_ratio']:.2f}x"
        lines.append(f"{row['spec']:26} {row['variant']:11} {row['rate_hz']:>5g} Hz  "
                     f"{share(row['plain_delay_s'], period):>17}  "
                     f"{share(row['predicted_delay_s'], period):>17}  {whole:>29}  "
                     f"{ratio:>9}")
    lines.append("plain law / predicted: the largest computation delay each sampled-data "
                 "check proves at the design's rate and gain (to 1/64 of the period); one "
                 "period: whether a delay of one whole period is certified; check CPU: one "
                 "predicted check over one plain check, both at the plain law's largest "
                 "delay (both pass there).")
    return "\n".join(lines)
