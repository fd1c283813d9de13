"""Published values the validation cases compare against, each with its source.

These are inputs or reference values printed in the papers' text or in tables that the seed copies keep
(``shared/reference/data/*.csv``). Result tables withheld from the seed copies (thesis Tables A2, A5–A11;
Hover et al. Tables III–V and the Fig. 2/6 data; Srivastava et al. Tables 2–3) are NOT reproduced here and
no value of them is guessed.
"""
from __future__ import annotations

THESIS = "Ranmuthugala (2000), shared/seeds/ranmuthugala-2000-two-part-and-multi-tow-thesis.txt"
HOVER = "Hover, Grosenbaugh & Triantafyllou (1994), shared/seeds/hover-1994-towed-cable-dynamics-and-heave-compensation.txt"
SRIVASTAVA = "Srivastava, Sanyasiraju & Tamsir, shared/seeds/srivastava-towed-cable-linear-profile.txt"

# Thesis Table 6.5 (L6604–6615): mean and standard deviation of (simulation - experiment), % of amplitude.
TABLE_6_5 = {
    ("I31", "fish", "pitch"): (-0.65, 13.72),
    ("I31", "fish", "heave"): (8.73, 19.45),
    ("I31", "fish", "surge"): (-0.21, 14.61),
    ("C31", "fish", "pitch"): (-2.75, 14.5),
    ("C31", "fish", "heave"): (8.6, 18.65),
    ("C31", "fish", "surge"): (0.52, 8.74),
    ("C31", "depressor", "pitch"): (-9.03, 11.57),
    ("C31", "depressor", "heave"): (-0.76, 17.72),
    ("C31", "depressor", "surge"): (2.79, 10.63),
    ("YA22", "fish", "yaw"): (-6.66, 10.99),
    ("YA22", "fish", "sway"): (-5.68, 15.49),
}

# Thesis Table 6.1 (L6275–6280): sonar motion-rate limits.
TABLE_6_1 = {"surge": (1.0, "m/s"), "sway": (1.0, "m/s"), "heave": (1.0, "m/s"),
             "roll": (6.28, "deg/s"), "pitch": (6.28, "deg/s"), "yaw": (1.05, "deg/s")}

# Thesis Tables 6.2 and 6.3 (printed in the text, L6308–6341): average % of samples exceeding the limits.
TABLE_6_2_3 = {
    "Trial 1 single": {"roll": 32.46, "pitch": 1.48, "yaw": 54.43, "surge": 0.59, "sway": 0.00, "heave": 0.00,
                       "any": 65.38},
    "Trial 1 two-part": {"roll": 1.06, "pitch": 0.05, "yaw": 10.04, "surge": 0.00, "sway": 0.00, "heave": 0.00,
                         "any": 10.78},
    "Trial 2 single": {"roll": 42.45, "pitch": 0.09, "yaw": 59.97, "surge": 0.00, "sway": 0.03, "heave": 0.25,
                       "any": 72.27},
    "Trial 2 two-part": {"roll": 12.86, "pitch": 0.16, "yaw": 30.58, "surge": 0.02, "sway": 0.00, "heave": 0.00,
                         "any": 36.80},
}
# the text's summary (L6345, L6369): "any" reduced by 83.51 % (Trial 1), 49.08 % (Trial 2), ~60 % (A11)
TRIAL_REDUCTION_PCT = {"Trial 1": 83.51, "Trial 2": 49.08, "Table A11 compatible pairs": 60.0}

# Hover et al. section IV-B (L331): SWATH deck significant heave height in sea state 6, available
# compensator travel, and the resulting requirement on |R/D|.
HOVER_SS6_DECK_H13 = 5.25     # m (height)
HOVER_TRAVEL = 4.0            # m (1/1000-highest stroke height allowed)
HOVER_R_OVER_D = 0.41         # the printed requirement |R(w)/D(w)| <= 0.41
HOVER_M_COMP = 530.0          # kg, Table II
# Hover Example 2 (L343–345): S-shaped tether
HOVER_S_ROV_WET_WEIGHT = 500.0    # N
HOVER_S_FLOAT_LENGTH = 75.0       # m
HOVER_S_FLOAT_BUOYANCY = 10.2     # N/m net buoyancy
HOVER_S_CABLE_LENGTH = 205.0      # m
HOVER_S_ROV_DEPTH = 100.0         # m
HOVER_S_CURRENT = 0.2             # m/s

# Srivastava et al. Table 1
SRIVASTAVA_TABLE_1 = [
    # segment, length (m), diameter (m), wet weight (N/m), C_t, C_n
    (1, 723.0, 0.04060, 2.3349, 0.01500, 2.0),
    (2, 8.23, 0.079375, 0.0, 0.00898, 1.8),
    (3, 71.02, 0.079375, 0.0, 0.00898, 1.8),
    (4, 156.36, 0.079375, 0.0, 0.00898, 1.8),
    (5, 38.71, 0.079375, 0.0, 0.00898, 1.8),
    (6, 30.48, 0.025400, 0.569134, 0.02168, 1.8),
]
SRIVASTAVA_CURRENT = 0.5      # m/s
