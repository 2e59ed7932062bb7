"""AEM baseline: reconstructs normal windows better than perturbed ones; seeded; saved/loaded."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from evoeye.baselines.aem import (
    AEMConfig,
    AEMMonitor,
    train_aem,
    window_vectors,
)
from evoeye.monitor.families import MonitorLoadError
from evoeye.monitor.protocol import Monitor

SMALL = AEMConfig(context_len=1, hidden=(48,), latent=4, epochs=30, batch_size=64, seed=3)


def traffic(n: int, seed: int, windows_of, obs, *, odd: bool = False):
    """n frames of 3 cars in lanes at moderate gaps and speeds; `odd`: erratic cars."""
    rng = np.random.default_rng(seed)
    frames = []
    for _ in range(n):
        cars = []
        for lane in (-4.0, 0.0, 4.0):
            if odd:
                cars.append(obs(rng.uniform(-10, 10), rng.uniform(-8, 8),
                                rng.uniform(-25, 25), rng.uniform(-6, 6)))
            else:
                cars.append(obs(rng.uniform(15, 60), lane + rng.normal(0, 0.2),
                                rng.normal(0, 1.0), rng.normal(0, 0.1)))
        frames.append(cars)
    return windows_of(frames, ego_speed_mps=list(rng.uniform(18, 25, n)))



def test_reconstructs_normal_frames_better_than_perturbed(windows_of, obs) -> None:
    train = traffic(600, 0, windows_of, obs)
    monitor = train_aem(train, np.ones(len(train), bool), SMALL)
    normal = monitor.score(traffic(200, 1, windows_of, obs))
    odd = monitor.score(traffic(200, 2, windows_of, obs, odd=True))
    assert np.median(odd) > np.quantile(normal, 0.9)
    assert ((normal >= 0) & (normal < 1)).all() and ((odd >= 0) & (odd < 1)).all()
    assert isinstance(monitor, Monitor) and monitor.context_len == 1


def test_training_uses_only_the_selected_windows(windows_of, obs) -> None:
    mixed = traffic(300, 0, windows_of, obs)
    normal = np.ones(len(mixed), bool)
    normal[::3] = False
    a = train_aem(mixed, normal, SMALL)
    b = train_aem(mixed.subset(np.flatnonzero(normal)), np.ones(normal.sum(), bool), SMALL)
    assert np.allclose(a.mean, b.mean) and a.version == b.version


def test_seeded_save_and_load(windows_of, obs, tmp_path: Path) -> None:
    train = traffic(300, 0, windows_of, obs)
    probe = traffic(50, 5, windows_of, obs)
    a = train_aem(train, np.ones(len(train), bool), SMALL)
    b = train_aem(train, np.ones(len(train), bool), SMALL)
    c = train_aem(train, np.ones(len(train), bool), AEMConfig(**{**SMALL.__dict__, "seed": 4}))
    assert a.version == b.version != c.version
    assert np.array_equal(a.score(probe), b.score(probe))
    folder = a.save(tmp_path, {"note": "test"})
    assert folder.name == a.version and (folder / "meta.json").is_file()
    loaded = AEMMonitor.load(folder)  # torch.load(weights_only=True) inside
    assert loaded.version == a.version and np.allclose(loaded.score(probe), a.score(probe))


def test_after_epoch_sees_each_epoch_s_aem_and_changes_no_weight(windows_of, obs) -> None:
    train, probe = traffic(300, 0, windows_of, obs), traffic(100, 2, windows_of, obs, odd=True)
    config = AEMConfig(**{**SMALL.__dict__, "epochs": 3})
    seen: list[tuple[int, float, float]] = []
    steps_per_epoch = -(-len(train) // config.batch_size)  # every window normal, none dropped

    def after_epoch(epoch: int, steps: int, aem: AEMMonitor) -> None:
        assert steps == epoch * steps_per_epoch
        seen.append((epoch, float(aem.errors(probe).mean()), aem.error_scale))

    plain = train_aem(train, np.ones(len(train), bool), config)
    followed = train_aem(train, np.ones(len(train), bool), config, after_epoch=after_epoch)
    assert followed.version == plain.version
    assert [e for e, _, _ in seen] == [1, 2, 3] and all(np.isnan(s) for _, _, s in seen)
    assert seen[-1][1] == pytest.approx(float(plain.errors(probe).mean()), rel=1e-6)
    assert len({err for _, err, _ in seen}) == 3  # the weights it sees move between epochs


def test_load_checks_the_sha256_in_meta(windows_of, obs, tmp_path: Path) -> None:
    import json

    train = traffic(100, 0, windows_of, obs)
    folder = train_aem(train, np.ones(len(train), bool), SMALL).save(tmp_path)
    meta = json.loads((folder / "meta.json").read_text())
    model = (folder / "model.pt").read_bytes()
    (folder / "model.pt").write_bytes(model[:-1] + bytes([model[-1] ^ 1]))
    with pytest.raises(MonitorLoadError, match="sha256 differs"):
        AEMMonitor.load(folder)
    (folder / "model.pt").write_bytes(model)
    del meta["model_sha256"]
    (folder / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(MonitorLoadError, match="no model_sha256"):
        AEMMonitor.load(folder)


def test_padded_context_slots_are_zeroed(windows_of, obs) -> None:
    w = traffic(4, 0, windows_of, obs)
    w.context_mask[:] = False  # as if every slot were padding
    assert not window_vectors(w).any()


def test_refuses_a_wrong_context_length_or_no_normal_window(windows_of, obs) -> None:
    w = traffic(10, 0, windows_of, obs)
    with pytest.raises(ValueError, match="L=1"):
        train_aem(w, np.ones(10, bool), AEMConfig(context_len=5))
    with pytest.raises(ValueError, match="collision-free"):
        train_aem(w, np.zeros(10, bool), SMALL)


def test_every_training_recipe_has_an_aem_part() -> None:
    # `evoeye results --recipe R` trains the AEM with R's part: a recipe without one crashed
    from evoeye.baselines.aem import AEM_RECIPES, aem_config
    from evoeye.monitor.recipes import RECIPES

    assert set(AEM_RECIPES) == set(RECIPES)
    for name in ("lookahead-v1",):  # it changes the FusionMonitor only
        assert aem_config(name) == aem_config("v3")
