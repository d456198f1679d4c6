"""What a resumed off-policy run could not restore, as ``note:`` lines.

A checkpoint restores the networks, optimisers, exploration, RNG states, the envs' running
episodes (on a ``JuggleBatchEnv``), the teacher's state and the replay buffers (reopened from the
run folder), so that a resumed run repeats an uninterrupted one. Three things can be missing: the
buffers' files (a checkpoint moved without its run folder), the episodes (``collector.env=gym``
cannot save them; a resume with another ``collector.num_envs`` cannot continue them) and, in a
buffer that was full, old frames that frames collected after the checkpoint replaced.
"""

from __future__ import annotations

from jugglerl.offpolicy.buffer import ReplayBuffer
from jugglerl.offpolicy.stages import Stage


def resume_notes(
    stages: list[Stage],
    frames: int,
    buffer: ReplayBuffer,
    buffers_restored: bool,
    episodes_restored: bool,
) -> list[str]:
    """The notes of a run resumed at ``frames`` (none for a new run): ``buffers_restored`` and
    ``episodes_restored`` say whether the checkpoint's buffers and episodes came back."""
    if frames == 0:
        return []
    notes = []
    if not buffers_restored:
        note = (
            f"note: resumed without the replay buffer's {min(frames, buffer.capacity)} frames"
            f" ({buffer.folder} does not hold them): the run learns from the frames it collects"
            " from here and does not repeat an uninterrupted one"
        )
        gone = [stage.name for stage in stages if stage.demonstrations and stage.start < frames]
        drawing = [stage.name for stage in stages if stage.demo_fraction and stage.end > frames]
        if gone and drawing:
            note += (
                f"; the demonstrations of stage {', '.join(gone)} collected before frame"
                f" {frames} are gone too, so stage {', '.join(drawing)} draws its demo_fraction"
                " only from those collected from here on"
            )
        notes.append(note)
    elif buffer.wrapped:
        notes.append(
            "note: the replay buffer was full at the checkpoint, so frames collected after it,"
            " before the run stopped, may have replaced some of its oldest: the run goes on but"
            " may not repeat an uninterrupted one"
        )
    if not episodes_restored:
        notes.append(
            "note: the envs start new episodes (collector.env=gym cannot save the running ones,"
            " and a checkpoint of another collector.num_envs cannot continue them): the run does"
            " not repeat an uninterrupted one"
        )
    return notes
