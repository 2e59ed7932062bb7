"""The flows' pydantic parameters of a campaign, built from `CampaignConfig`'s options.

`campaign_model` adds one pydantic field per campaign option (`campaign_options`: type, default,
bounds, help, and the registry's names as the JSON schema's enum) to a base model holding what
the flow adds itself; `KnownNames` checks every field that names registered things. So an option
is declared once, in `evoeye.evolve.campaign.config`, for the flows as for the command line.
`flat_parameters` gives a flow such a model's fields as its own parameters (the nightly
deployment's, which a flow run may then override one at a time).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Collection
from typing import Annotated, Any, ClassVar, TypeVar

from pydantic import BaseModel, Field, create_model, model_validator

from evoeye.evolve.campaign.config import campaign_options, check_known, known

F = TypeVar("F", bound=Callable[..., Any])


class KnownNames(BaseModel):
    """A model whose name-valued fields are checked against their registries (KNOWN kinds)."""

    names: ClassVar[dict[str, str]] = {}  # field → KNOWN kind, besides the campaign options'

    @model_validator(mode="after")
    def _known(self) -> KnownNames:
        kinds = {o.name: o.names for o in campaign_options() if o.names} | self.names
        for name, kind in kinds.items():
            if name in type(self).model_fields:
                value = getattr(self, name)
                check_known(kind, value if isinstance(value, list) else [value])
        return self


def campaign_fields(exclude: Collection[str] = ()) -> dict[str, Any]:
    """pydantic field definitions of the campaign options (minus `exclude`)."""
    out: dict[str, Any] = {}
    for o in campaign_options(exclude):
        kind = o.type | None if o.optional else o.type
        extra = {"enum": sorted(known(o.names))} if o.names else None
        out[o.name] = (kind, Field(o.default, ge=o.ge, gt=o.gt, le=o.le, description=o.help,
                                   json_schema_extra=extra))
    return out


def campaign_model(name: str, base: type[KnownNames], module: str,
                   exclude: Collection[str] = ()) -> type[KnownNames]:
    """`base` with a field per campaign option, as the class `name` of `module`."""
    model = create_model(name, __base__=base, __module__=module, **campaign_fields(exclude))
    model.__doc__ = base.__doc__
    return model


def flat_parameters(model: type[BaseModel]) -> Callable[[F], F]:
    """Decorator: a `**fields` function takes the fields of `model` as keyword-only parameters
    (type, bounds, names and default of each; its help in the docstring's Args section), so
    that a flow made of it has them as its own parameters: Prefect's form and schema show
    each, and a flow run may set one alone (`--param budget_s=800`)."""
    def flat(fn: F) -> F:
        params = [inspect.Parameter(
            name, inspect.Parameter.KEYWORD_ONLY,
            annotation=Annotated[field.annotation, *field.metadata,
                                 Field(json_schema_extra=field.json_schema_extra)],
            default=field.get_default(call_default_factory=True))
            for name, field in model.model_fields.items()]
        fn.__signature__ = inspect.Signature(params)  # type: ignore[attr-defined]
        helps = [f"    {name}: {' '.join((field.description or name).split())}"
                 for name, field in model.model_fields.items()]
        fn.__doc__ = "\n".join([inspect.cleandoc(fn.__doc__ or ""), "", "Args:", *helps])
        return fn
    return flat
