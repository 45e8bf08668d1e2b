"""Contacts grouped into collisions (app/collisions.py), against the rule written out."""

from __future__ import annotations

import numpy as np
import pytest

import twoball
from app.collisions import collisions
from twoball.stacks import simulate_stack


def by_the_rule(contacts: list) -> list[list]:
    """The rule, with each collision's end worked out again at every contact: a contact joins
    the current collision if it starts within the collision's duration so far after its end."""
    groups: list[list] = []
    for contact in sorted(contacts, key=lambda c: c.start):
        if groups:
            start, stop = groups[-1][0].start, max(c.end for c in groups[-1])
            if contact.start <= stop + (stop - start):
                groups[-1].append(contact)
                continue
        groups.append([contact])
    return groups


@pytest.mark.parametrize("seed", range(5))
def test_collisions_follow_the_rule_for_random_contacts(seed):
    rng = np.random.default_rng(seed)
    starts = np.cumsum(rng.exponential(1.0, 400) * rng.choice([0.05, 1.0, 20.0], 400))
    contacts = [
        twoball.ContactInterval(int(rng.integers(0, 3)), float(t), float(t + rng.exponential(2.0)))
        for t in rng.permutation(starts)
    ]
    assert collisions(contacts) == by_the_rule(contacts)


def test_an_eight_ball_stack_s_thousands_of_contacts_group_as_the_rule_says():
    result = simulate_stack([0.2] * 7, 0.9, 0.2, height=1e4)
    assert len(result.contacts) > 5000
    assert collisions(result.contacts) == by_the_rule(result.contacts)
