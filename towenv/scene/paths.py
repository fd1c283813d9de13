"""Where the embedded scenes live, and the project's default scene.
"""
from pathlib import Path





SCENES_DIR = Path(__file__).resolve().parent.parent / "scenes"


SCENE_DATA_DIR = SCENES_DIR / "data"


DEFAULT_SCENE = "two_part_tow_1"
