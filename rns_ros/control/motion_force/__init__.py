"""Motion/force control of fixed-base redundant arms, thesis Part II chapters 6-7.

Task space and outer loops (6.10)-(6.12), (6.33)-(6.34); OS-C (6.6)-(6.13); the reversed RNS-C
control model (6.14)-(6.32) and its law; the chapter-7 null-space terms. Conventions:
docs/part2_controllers.md.
"""
