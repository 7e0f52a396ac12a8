# Turn the validated config into targets and job parameters.
import json

PY = sys.executable
RES = "results"


def up_tag(u):
    """Wildcard text of a piston velocity (e.g. 0.5 -> '0.5', 2.0 -> '2')."""
    return f"{float(u):.6g}"


def scene_json(wildcards):
    scene = dict(config["scenes"][wildcards.scene])
    scene["name"] = wildcards.scene
    return json.dumps(scene, sort_keys=True)


def point_files(wildcards):
    ups = config["scenes"][wildcards.scene]["shock"]["u_p"]
    return [f"{RES}/{wildcards.scene}/up{up_tag(u)}/piston.nc" for u in ups]


def all_targets():
    out = []
    for scene in config["scenes"]:
        out += [
            f"{RES}/hugoniot/{scene}.nc",
            f"{RES}/figures/{scene}_PV.png",
            f"{RES}/figures/{scene}_D_up.png",
        ]
    return out
