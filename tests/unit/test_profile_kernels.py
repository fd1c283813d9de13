"""scripts/profile_kernels.py's attribution of perf samples to numba functions (the perf run itself is a benchmark,
not a test): mangled names shorten to module.function, and a sample goes to the nearest function start below it."""
from __future__ import annotations

from helpers import load_script


def test_short_names_and_nearest_start_attribution():
    pk = load_script("profile_kernels")
    adv = "_ZN6towenv4core7houbolt7advanceB3v18B46c8tJTIeFIjxB2IKSgI4CrvSCKg1MMbCQQPKkLTj8NAE_3dExd5ArrayIdLi2E1C7"
    seg = "_ZN6towenv4core11cable_loads13segment_loadsB3v36B54c8tJTIeFIjxB2I"
    assert pk.short_name(adv) == "houbolt.advance"
    assert pk.short_name(seg) == "cable_loads.segment_loads"
    assert pk.short_name("_ZN7cpython" + adv[3:]) == "cpython wrapper of houbolt.advance"
    assert pk.short_name("not_mangled") == "not_mangled"
    symbols = {adv: 0x1000, seg: 0x2000}
    inside, outside = pk.attribute([0x1000, 0x1fff, 0x2000, 0x2500, 0x0fff, 0x2000 + (1 << 20)], symbols)
    assert inside == {"houbolt.advance": 2, "cable_loads.segment_loads": 2} and outside == 2
