"""``TensorModule``: a ``TensorDictModule`` that writes plain tensor outputs straight in.

tensordict 0.14 passes every module output through ``TensorDict.from_any``, which for a plain
tensor ends in ``importlib.util.find_spec("pandas")``: ≈ 0.15 ms a call, 5 % of an update (five
network calls) and of a collection step. Anything else (an output tensordict,
``inplace=False``) takes the parent's path. The actors and critics are built from it.
"""

from __future__ import annotations

from tensordict.nn import TensorDictModule


class TensorModule(TensorDictModule):
    def _write_to_tensordict(self, tensordict, tensors, tensordict_out=None, out_keys=None):
        if tensordict_out is not None or self.inplace is not True:
            return super()._write_to_tensordict(tensordict, tensors, tensordict_out, out_keys)
        for key, tensor in zip(out_keys or self.out_keys_source, tensors, strict=True):
            if key != "_":
                tensordict.set(key, tensor)
        return tensordict
