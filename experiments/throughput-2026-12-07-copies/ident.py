"""Train 4 steps (bfloat16 and float32) on 8 scenes and save the weights, to compare code versions bit for bit."""
import sys, tempfile, torch
from assist3d.learn.segmenter.probe import load_training_scenes
from assist3d.learn.segmenter.config import parse_segmenter_config
from assist3d.learn.segmenter.train import train_segmenter, Budget
from assist3d.learn.segmenter.checkpoint import load_segmenter
out = sys.argv[1]
scenes = load_training_scenes(["assist3d:/work/tmp/scaling/data"], 8)
res = {}
for prec in ("bfloat16", "float32"):
    cfg = parse_segmenter_config({"optim": {"precision": prec}}, "x")
    with tempfile.TemporaryDirectory() as tmp:
        rec = train_segmenter(cfg, scenes, tmp, seed=3, budget=Budget(steps=4))
        m = load_segmenter(rec.checkpoint, "cpu", weights="live").model
        res[prec] = {k: v.clone() for k, v in m.state_dict().items()}
        print(prec, rec.last_loss)
torch.save(res, out)
