"""problems.cache: entries are reused while their key matches and refitted when it changes."""
from __future__ import annotations


from problems.cache import cache_key, cache_path, cached_entries, key_hash, read_cache
from problems.evaluate import fit_and_evaluate
from problems.settings import EvalConfig, shape


def test_cache_is_reused_and_keyed(toy, toy_shape, toy_config, fast_methods):
    ctx, entries = toy
    again = fit_and_evaluate(toy_shape, "GMR", config=toy_config, cache_dir=ctx.cache_dir)
    assert again["from_cache"] and again["accuracy"] == entries[toy_shape.name]["GMR"]["accuracy"]
    other = EvalConfig(**{**toy_config.key(), "n_grid": 4})
    assert read_cache(toy_shape, "GMR", other, ctx.cache_dir) is None
    assert cached_entries((toy_shape,), fast_methods, config=toy_config, cache_dir=ctx.cache_dir)[toy_shape.name].keys() \
        == set(fast_methods)


def test_key_and_path(toy_shape, toy_config):
    key = cache_key(shape("Leaf_2"), "CDSP-ICA", toy_config)
    assert key["shape"] == {"name": "Leaf_2", "K": 6, "dmp_basis": 35} and key["settings"]["solver_method"] == "ica"
    assert len(key_hash(key)) == 16 and key_hash(key) == key_hash(dict(reversed(list(key.items()))))
    assert cache_path(shape("Leaf_2"), "CDSP (paper)", toy_config, "c").name == "Leaf_2__CDSP__paper___quick.json"
    assert cache_path(toy_shape, "GMR", EvalConfig(), "c").name == "Leaf_1__K3__GMR.json"
