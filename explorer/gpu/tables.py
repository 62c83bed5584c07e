"""
The numpy models behind the materials' tables (:func:`explorer.materials.models.model_for`), kept in a small
least-recently-used cache: an interactive session goes back and forth between a few parameter sets (a
slider and its start, compare A | B), and a table costs ~10 ms. Filling it needs no GL, so an
interactive host can build the next tables on a worker thread while it draws.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass
from typing import Mapping

from explorer.materials.brd import Material
from explorer.materials.models import model_for
from explorer.materials.twins import twin_class

#: Numpy models (and their tables) kept by :class:`ModelCache`.
MODEL_CACHE_SIZE = 8


@dataclass
class CacheEntry:
    """A cached model: the numpy twin, its tables (``textures()``; None until asked), and whether those
    are its quick ``draft_textures()`` (shown while a slider moves, replaced on :meth:`ModelCache.prepare`)."""

    model: object
    tables: dict | None = None
    draft: bool = False

    def ensure_tables(self) -> dict:
        """The tables, built from the model on first use."""
        if self.tables is None:
            self.tables = self.model.textures()
        return self.tables


class ModelCache:
    """
    ``(material path, model, values) ->`` :class:`CacheEntry`, least recently used first.
    """

    def __init__(self, size: int = MODEL_CACHE_SIZE):
        self.size = size
        self._models: OrderedDict[tuple, CacheEntry] = OrderedDict()
        self._lock = threading.Lock()  # prepare() may fill the cache from another thread

    @staticmethod
    def key(material: Material, values: Mapping[str, object]) -> tuple | None:
        """The cache key of ``material``'s model at physical ``values`` (None: an unhashable value, not cached)."""
        try:
            key = (str(material.path), material.model, tuple(sorted(values.items())))
            hash(key)
        except TypeError:  # an unhashable value (a list)
            return None
        return key

    def entry(self, material: Material, values: Mapping[str, object]) -> tuple[tuple | None, CacheEntry | None]:
        """
        ``(key, entry)`` of ``material`` at ``values`` (entry None: it has no model), from the cache or
        built here; key None: uncached. The entry's tables are None until someone asks for them.
        """
        values = material.typed_values(values)
        key = self.key(material, values)
        if key is None:
            model = model_for(material, values)
            return None, (CacheEntry(model) if model is not None else None)
        with self._lock:
            entry = self._models.get(key)
            if entry is not None:
                self._models.move_to_end(key)
                return key, entry
        model = model_for(material, values)
        if model is None:
            return key, None
        return key, self._store(key, CacheEntry(model))

    def _store(self, key: tuple, entry: CacheEntry) -> CacheEntry:
        with self._lock:
            self._models[key] = entry
            self._models.move_to_end(key)
            while len(self._models) > self.size:
                self._models.popitem(last=False)
        return entry

    def ready(self, material: Material, values: Mapping[str, object]) -> bool:
        """Whether ``material`` at ``values`` needs no numpy work (its tables are cached, or it has none)."""
        if twin_class(material) is None:
            return True
        key = self.key(material, material.typed_values(values))
        with self._lock:
            entry = self._models.get(key) if key is not None else None
        return entry is not None and entry.tables is not None and not entry.draft

    def drawable(self, material: Material, values: Mapping[str, object]) -> bool:
        """Whether ``material`` at ``values`` can be drawn without numpy work, its draft tables accepted."""
        if self.ready(material, values):
            return True
        key = self.key(material, material.typed_values(values))
        with self._lock:
            entry = self._models.get(key) if key is not None else None
        return entry is not None and entry.tables is not None

    def prepare(self, material: Material, values: Mapping[str, object]) -> None:
        """Build ``material``'s model at ``values`` and its tables into the cache; safe on a worker thread."""
        if self.ready(material, values):
            return
        values = material.typed_values(values)
        key = self.key(material, values)
        model = model_for(material, values)
        if model is None or key is None:
            return
        self._store(key, CacheEntry(model, model.textures(), False))

    def prepare_draft(self, material: Material, values: Mapping[str, object]) -> bool:
        """
        Store ``material``'s quick draft tables at ``values`` (its model's ``draft_textures()``) unless real
        or draft ones are there; True when ``values`` can be drawn now without building the real tables.
        """
        if self.ready(material, values):
            return True
        values = material.typed_values(values)
        key = self.key(material, values)
        if key is None:
            return False
        with self._lock:
            entry = self._models.get(key)
        if entry is not None and entry.draft:
            return True
        model = entry.model if entry is not None else model_for(material, values)
        draft = getattr(model, "draft_textures", lambda: None)() if model is not None else None
        if draft is None:
            return False
        self._store(key, CacheEntry(model, draft, True))
        return True
