"""Every case of the corpus, by reader (one module per family of inputs)."""

import cases_datasets
import cases_eval
import cases_models
import cases_settings


def all_specs(inputs, seed):
    specs = (cases_settings.specs(inputs, seed) + cases_datasets.specs(inputs, seed) +
             cases_eval.specs(inputs, seed) + cases_models.specs(inputs, seed))
    names = set()
    for spec in specs:  # a name is a folder: make each unique
        base, k = spec.name, 1
        while (spec.reader, spec.name) in names:
            k += 1
            spec.name = f"{base}_{k}"
        names.add((spec.reader, spec.name))
    return specs
