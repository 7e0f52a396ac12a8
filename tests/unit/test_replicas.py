"""Replica statistics (hugomap.analysis.replicas).

Reference: for normal deviations e_i ~ N(μ, s_i) the pooled Σ(e − ē)²/s² over groups is
χ² with Σ(n − 1) degrees of freedom, so χ²/ν has mean 1 and standard deviation √(2/ν):
0.033 for the 1800 degrees of freedom drawn here, so a 0.15 bound is 4.5 of them; errors
stated half their true size give 4, a shared bias μ moves the RMS pull to √(1 + (μ/s)²)
but not χ²/ν."""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.analysis.replicas import against_base, replica_cases, replica_summary


def _draw(scale_err: float, bias: float, seed: int = 5):
    rng = np.random.default_rng(seed)
    groups, e, s = [], [], []
    for g in range(200):
        sig = 0.002 * (1 + g % 3)
        for _ in range(10):
            groups.append(("piston", g))
            e.append(bias * sig + sig * rng.standard_normal())
            s.append(sig * scale_err)
    return groups, np.array(e), np.array(s)


def test_honest_errors_give_chi2_near_one_and_unit_pulls():
    out = replica_summary(*_split(_draw(1.0, 0.0)))
    assert abs(out["D_chi2_red"] - 1.0) < 0.15
    assert abs(out["D_pull_rms"] - 1.0) < 0.1


def test_errors_too_small_show_in_chi2():
    out = replica_summary(*_split(_draw(0.5, 0.0)))
    assert abs(out["D_chi2_red"] - 4.0) < 0.6


def test_a_shared_bias_shows_in_the_pulls_not_in_chi2():
    out = replica_summary(*_split(_draw(1.0, 2.0)))
    assert abs(out["D_chi2_red"] - 1.0) < 0.15
    assert abs(out["D_pull_rms"] - np.sqrt(5.0)) < 0.15


def test_a_replica_case_sets_only_the_seed():
    camp = {"cases": {"a": {"resolutions": {"s1": {"sample.seed": 1}, "s2": {"sample.seed": 2}}},
                      "b": {"resolutions": {"lo": {"sample.cells": [8, 4, 4]},
                                            "hi": {"sample.seed": 3}}},
                      "c": {"resolutions": {"s1": {"sample.seed": 1}}}}}  # fmt: skip
    assert replica_cases(camp) == ["a"]


def test_against_base_pairs_each_point_with_its_one_base():
    """d = e − e_base with the errors in quadrature; a key without a base, or with two,
    pairs nothing, and the base is not paired with itself."""
    pairs = [("s1", 1), ("s1", 1), ("s2", 1), ("s3", 1), ("s3", 1), ("s3", 1)]
    schemes = ["piston", "amw", "amw", "piston", "piston", "mw"]
    e = np.array([0.01, 0.04, 0.02, 0.0, 0.0, 0.0])
    s = np.array([0.003, 0.004, 0.001, 0.001, 0.001, 0.001])
    idx, d, sd = against_base(pairs, schemes, e, s)
    assert idx == [1]
    assert d == pytest.approx([0.03]) and sd == pytest.approx([0.005])


def _split(d):
    groups, e, s = d
    return groups, {"D": (e, s)}
