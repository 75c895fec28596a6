"""Body pairs whose self-collision is switched off, and why.

MuJoCo already ignores contacts inside a weld group (a body without joints welds to its
parent: hip joints to the root, upperneck to lowerneck, wrists to the forearm, fingers to
the hand, thumbs to the wrist, hence to the forearm) and between a weld group and its
parent's weld group (``body_weldid``). Every other pair of bodies can collide, except the
pairs below, and only these: each one overlaps in the standing rest pose of at least one
of the twelve CMU subjects, by construction of the capsules (the test suite checks that
every pair listed is needed and that the rest pose is then free of self-contact).

Pairs not listed stay on even where real motion makes them touch (hands on hips, arms
against the chest, thighs together, a deeply flexed trunk): those contacts are real and
are reported, never hidden. An ``<exclude>`` names exact bodies: a pair with a welded body
(for example upperneck, which carries no geom here) would need its own entry.
"""

from __future__ import annotations

#: (body1, body2, reason) for every excluded pair.
EXCLUDED_PAIRS: tuple[tuple[str, str, str], ...] = (
    ("lclavicle", "lowerneck", "the clavicle starts at the base of the neck (overlap at rest "
                               "on every subject)"),
    ("rclavicle", "lowerneck", "the clavicle starts at the base of the neck (overlap at rest "
                               "on every subject)"),
    ("lclavicle", "rclavicle", "both clavicles start at the top of the sternum (overlap at "
                               "rest where the clavicles are short: subject 83)"),
    ("lowerback", "lfemur", "the top of the thigh sits against the lower abdomen at the hip "
                            "(overlap at rest on subjects with close hip joints: 35, 60, 131)"),
    ("lowerback", "rfemur", "as for the left thigh"),
)
