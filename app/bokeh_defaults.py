"""Bokeh's property defaults worked out once per class instead of once per model.

Every Bokeh model a page builds asks each of its properties for a default it has not been given:
the class's overridden defaults merged along its MRO, the raw default copied, validated and
transformed (``Property.themed_default``), and whether that default must be kept per instance
(``PropertyDescriptor.has_unstable_default``). None of it depends on the instance, only on the
class and the property, yet Bokeh 3.9 redoes it for each model and again when the document is
serialised: about a sixth of a page's opening cost here (benchmarks/app_open.py prints both).

:func:`cache_property_defaults` keeps each answer per (class, property): an answer that cannot
be changed in place (numbers, strings, None, tuples of them) is shared; an empty list, dict or
set (a third of the questions: every model's tags, style sheets, callbacks) is built again,
empty, for each model; any other default (a model, a list with items) is computed by Bokeh for
each model, as before. A theme's own value for a
property (a document theme) still goes through Bokeh's code. tests/app/test_app_hooks.py
compares every property of every model class with Bokeh's own answers.

:func:`themed_values_read_directly` answers Bokeh's other per-property question, whether a
document theme gave the model a value, without raising an exception when none did.
"""

from __future__ import annotations

from typing import Any

from bokeh.core.has_props import HasProps
from bokeh.core.property.bases import Property
from bokeh.core.property.descriptors import PropertyDescriptor
from bokeh.core.property.singletons import UndefinedType

_IMMUTABLE = (int, float, str, bool, type(None), UndefinedType)


def unchangeable(value: Any) -> bool:
    """Whether ``value`` can be shared by every model (nothing in it can be changed in place)."""
    if isinstance(value, _IMMUTABLE):
        return True
    return isinstance(value, tuple) and all(unchangeable(item) for item in value)


def empty_container(value: Any) -> bool:
    """Whether ``value`` is an empty list, dict or set that its type builds again with no
    arguments (Bokeh's property containers too): each model then gets a new one."""
    return isinstance(value, (list, dict, set)) and not value and type(value)() == value


def cache_property_defaults() -> None:
    """Answer Bokeh's per-model default questions from a per-class cache. Idempotent."""
    if getattr(Property.themed_default, "cached", False):
        return
    themed_default = Property.themed_default
    unstable = PropertyDescriptor.has_unstable_default
    overridden = HasProps._overridden_defaults.__func__
    # keyed by id(): Bokeh's properties do not hash; the property itself is kept in the entry
    # and compared, so that a key reused by a new object after a class was deleted never matches
    defaults: dict[tuple, tuple] = {}
    unstable_by_class: dict[tuple, tuple] = {}
    overrides_by_class: dict[type, dict] = {}

    def cached_themed_default(self, cls, name, theme_overrides, *, no_eval=False):
        if theme_overrides is not None and name in theme_overrides:
            return themed_default(self, cls, name, theme_overrides, no_eval=no_eval)
        key = (id(self), cls, name, no_eval)
        entry = defaults.get(key)
        if entry is not None and entry[0] is self:
            shared, value = entry[1:]
            return value if shared else type(value)()
        value = themed_default(self, cls, name, theme_overrides, no_eval=no_eval)
        if unchangeable(value):
            defaults[key] = (self, True, value)
        elif empty_container(value):
            defaults[key] = (self, False, value)
        return value

    def cached_has_unstable_default(self, obj):
        key = (id(self), type(obj))
        entry = unstable_by_class.get(key)
        if entry is None or entry[0] is not self:
            entry = unstable_by_class[key] = (self, unstable(self, obj))
        return entry[1]

    def cached_overridden_defaults(cls):
        # (read, never changed, by Property.themed_default, its one caller)
        if cls not in overrides_by_class:
            overrides_by_class[cls] = overridden(cls)
        return overrides_by_class[cls]

    cached_themed_default.cached = True
    cached_themed_default.__wrapped__ = themed_default
    Property.themed_default = cached_themed_default
    PropertyDescriptor.has_unstable_default = cached_has_unstable_default
    HasProps._overridden_defaults = classmethod(cached_overridden_defaults)


def themed_values_read_directly() -> None:
    """Bokeh reads a model's theme values with ``getattr(model, "__themed_values__", None)``;
    a model no theme applies to (every model here: the app sets no document theme) has no
    such attribute, so each read raised and caught an AttributeError through
    ``HasProps.__getattr__``. Bokeh asks at every default it works out, about 14 000 times a
    page: 18 ms of a page's 150 (benchmarks/app_open.py, alternating, drop). The attribute
    is only ever set on the model itself (``HasProps.apply_theme``), so it is read from the
    model's ``__dict__``; tests/app/test_app_hooks.py compares the answers with Bokeh's for
    models with and without a theme. Idempotent."""
    if getattr(HasProps.themed_values, "direct", False):
        return

    def themed_values(self) -> dict[str, Any] | None:
        return self.__dict__.get("__themed_values__")

    themed_values.direct = True
    themed_values.__wrapped__ = HasProps.themed_values
    themed_values.__doc__ = HasProps.themed_values.__doc__
    HasProps.themed_values = themed_values
