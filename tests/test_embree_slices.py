"""The CPU backend hands Embree a moving group's segment keys as several instances of at most nine
time steps, each valid over its part of the segment (cpu_backend.c, SLICE_KEYS): the same motion
as one instance of every key, only faster. In a blink of the eye (segments of 65 keys) the events
equal those of one instance per group (EVR_NO_EMBREE_SLICES), with and without change-driven
sampling; an instance's slice that answered outside its time (Embree 3.13.5's packet occlusion
test does) would shadow the eye and add events."""
import os

import evrtest as T

tmp = T.tmpdir()
for extra in ([], ["--no-skip"], ["--sensor", "davis346"]):
    out = {}
    for env in (None, "EVR_NO_EMBREE_SLICES"):
        d = os.path.join(tmp, f"{'-'.join(extra) or 'skip'}-{env or 'slices'}")
        T.run_env(env, "demo", "--scene", "eye", "--backend", "cpu", "--res", "96x72", "--start", "0.6", "--duration", "0.3",
                  "--format", "npy", "--no-preview", "--quiet", "--seed", "5", "-o", d, *extra)
        out[env] = (open(os.path.join(d, "events.npy"), "rb").read(), T.load_run_json(d)["stats"]["events"])
    (a, na), (b, nb) = out[None], out["EVR_NO_EMBREE_SLICES"]
    print(f"{' '.join(extra) or 'skip'}: {na} events with slices, {nb} with one instance per group")
    T.check(na > 1000, f"{extra}: the blink makes events")
    T.check(a == b, f"{extra}: identical events with and without Embree time slices")
T.finish("test_embree_slices")
