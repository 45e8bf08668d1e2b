"""Contacts grouped into collisions: what the close-up zooms on and the animation slows down for."""

from __future__ import annotations

import twoball
from twoball.observables import BALLS


def collisions(contacts: list[twoball.ContactInterval]) -> list[list[twoball.ContactInterval]]:
    """The contacts grouped into collisions, in time order.

    A contact belongs to the current collision if it starts less than the collision's duration
    so far after the collision's end: the balls' several contacts during one floor contact are
    one collision, the lower ball's next floor bounce, long after, starts another.
    """
    groups: list[list[twoball.ContactInterval]] = []
    stop = 0.0  # the current collision's end so far (kept, not recomputed: an eight-ball stack
    # has thousands of contacts, and the max over each group at each contact took 0.7 s a move)
    for contact in sorted(contacts, key=lambda c: c.start):
        if groups and contact.start <= stop + (stop - groups[-1][0].start):
            groups[-1].append(contact)
            stop = max(stop, contact.end)
            continue
        groups.append([contact])
        stop = contact.end
    return groups


def shown_collisions(contacts: list[twoball.ContactInterval]) -> list[twoball.ContactInterval]:
    """The contacts the close-up shows (:func:`collisions`): the first collision's, and, when
    the balls do not touch in it, those of the collisions up to the one in which they first do.
    At a large gap the lower ball's floor bounce comes alone, long before the balls meet in the
    air: its plots showed a flat force between the balls (a teacher's trial, tau_d/tau_f = 10)."""
    shown: list[twoball.ContactInterval] = []
    for collision in collisions(contacts):
        shown += collision
        if any(c.contact == BALLS for c in collision):
            break
    return shown
