"""`use_template NAME(ARGS)` in `.lnc` files, a part of the Parser (parser.py): finds the
template among the name prefixes in effect, binds its parameters and reads its body as if it
stood at the line of the use (templates.py holds the templates themselves)."""

from __future__ import annotations

from .drafts import Ctx, Drafts
from .errors import Gather, LineError, did_you_mean, relative, shift
from .model import Location
from .templates import Template, check_arity, split_call
from .text import Piece

MAX_TEMPLATE_DEPTH = 32


class TemplateUse:
    """The Parser's template uses; uses its state (below) and its `value`, `scopes` and
    `run`."""

    drafts: Drafts
    templates: dict[str, Template]

    def use_template(self, piece: Piece, ctx: Ctx) -> None:
        if "%(" in piece.text:  # `use_template: %(name)`: the name is computed
            piece = Piece(self.value(piece, ctx).text.strip(), piece.loc)
        name, args = split_call(piece.text, piece.loc)
        template = self.find_template(name, piece.loc)
        if len(ctx.chain) >= MAX_TEMPLATE_DEPTH:
            raise LineError.at(piece.loc, f"templates nested more than {MAX_TEMPLATE_DEPTH} "
                                          "deep")
        if template.name in ctx.chain:
            chain = " -> ".join([*ctx.chain[ctx.chain.index(template.name):], template.name])
            raise LineError.at(piece.loc, f"template recursion: {chain}")
        given = args or []
        check_arity(template, len(given), piece.loc)
        bound: dict[str, str] = {}
        gather = Gather()
        for param, (text, offset) in zip(template.params, given, strict=False):
            try:
                bound[param.name] = self.value(Piece(text, shift(piece.loc, offset)), ctx).text
            except LineError as exc:
                gather.add(exc)
        for param in template.params[len(given):]:
            assert param.default is not None
            try:
                inner = Ctx(param.loc.file, dict(bound))
                bound[param.name] = self.value(Piece(param.default, param.loc), inner).text
            except LineError as exc:
                gather.add(exc)
        gather.check()
        where = f"{relative(piece.loc.file, self.drafts.root)}:{piece.loc.line}:{piece.loc.col}"
        use = f"template '{template.name}' used at {where}"
        self.run(template.body, Ctx(ctx.file, bound, (use, *ctx.uses),
                                    (*ctx.chain, template.name)))

    def find_template(self, name: str, loc: Location) -> Template:
        for scope in self.scopes():
            full = f"{scope}/{name}" if scope else name
            if full in self.templates:
                return self.templates[full]
        raise LineError.at(loc, f"unknown template '{name}'"
                                f"{did_you_mean(name, self._template_names())}")

    def _template_names(self) -> list[str]:
        names = list(self.templates)
        for scope in self.scopes():
            if scope:
                names += [n[len(scope) + 1:] for n in self.templates if n.startswith(scope + "/")]
        return names
