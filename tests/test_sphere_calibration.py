"""Sensor mount calibration with a reference sphere (``machscan.calibrate_mount_sphere``) against
the synthetic truth: the mount and the sphere's centre through 8 µm of profiler noise from 3 to 8
poses, the stated uncertainty covering the error, and a pose set that cannot determine the
mount refused by name."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import machscan
from machscan.synth import sphere_scan


@pytest.mark.parametrize("poses", [3, 5, 8])
def test_the_mount_and_the_centre_are_recovered_within_target(poses):
    worst = np.zeros(3)
    for seed in range(3):
        scan, truth = sphere_scan(poses, noise=0.008, seed=seed)
        cal = machscan.calibrate_mount_sphere(scan, truth.radius)
        assert cal.converged
        err = cal.params - truth.mount
        worst = np.maximum(worst, [np.abs(err[:3]).max(), np.abs(err[3:]).max(), np.abs(cal.sphere_center - truth.center).max()])
        # The stated standard errors cover the error (k = 4: three seeds, nine parameters).
        sigma = cal.std_errors
        both = np.concatenate([err, cal.sphere_center - truth.center])
        assert np.all(np.abs(both) <= 4 * sigma), (both / sigma).round(1)
        assert cal.rms == pytest.approx(0.008, rel=0.35)
    assert worst[0] <= 0.05e-3, f"mount angles {worst[0] * 1e3:.4f} mrad"
    assert worst[1] <= 0.005, f"mount shift {worst[1] * 1e3:.2f} µm"
    assert worst[2] <= 0.005, f"centre {worst[2] * 1e3:.2f} µm"


def test_the_calibrated_mount_puts_every_point_on_the_sphere():
    scan, truth = sphere_scan(5, noise=0.0)
    cal = machscan.calibrate_mount_sphere(scan, truth.radius)
    points, _ = dataclasses.replace(scan, mount=cal.params).wcs_points()
    np.testing.assert_allclose(np.linalg.norm(points - cal.sphere_center, axis=1), truth.radius, atol=1e-6)
    assert "sphere x" in cal.summary() and cal.covariance.shape == (9, 9)


def test_poses_that_see_the_sphere_alike_are_refused_naming_what_to_add():
    scan, truth = sphere_scan(1, noise=0.0)
    with pytest.raises(ValueError, match=r"scan: the poses do not determine .*turn the sensor differently"):
        machscan.calibrate_mount_sphere(scan, truth.radius)
    with pytest.raises(ValueError, match="radius"):
        machscan.calibrate_mount_sphere(scan, 0.0)
    with pytest.raises(ValueError, match="mount"):
        machscan.calibrate_mount_sphere(scan, 12.7, init=[0.0] * 5)


def test_the_cli_calibrates_from_a_saved_scan_and_writes_the_mount(tmp_path, capsys):
    from machscan.cli import main

    scan, truth = sphere_scan(4, seed=1)
    scan.save(tmp_path / "sphere.npz")
    out = tmp_path / "mount.txt"
    assert main(["calibrate", str(tmp_path / "sphere.npz"), "--radius", str(truth.radius), "--out", str(out)]) == 0
    mount = np.loadtxt(out)
    assert mount.shape == (6,) and np.abs(mount - truth.mount)[3:].max() < 0.005
    assert "sphere x" in capsys.readouterr().out
    assert main(["calibrate", "--simulate", "--out", str(tmp_path / "sim.txt")]) == 0
    assert main(["calibrate", str(tmp_path / "sphere.npz"), "--out", str(out)]) == 2  # no --radius
