"""The configuration's typed sections, one per pipeline stage, composed by ``GenerateConfig``.
Every field states its paper default (if any).
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from ..core.taxonomy.roomtypes import ROOM_TEMPLATES


class Section(BaseModel):
    """The base of every configuration schema: generation (here), training (:mod:`assist3d.learn.engine.config`)
    and the CPU segmenter (:mod:`assist3d.learn.segmenter.config`). Unknown keys are refused (with the closest
    known key, see :func:`.files.validate_config`), assignments are validated, NaN and infinity are refused."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True, allow_inf_nan=False)


class AssetsConfig(Section):
    """Where assets come from."""

    library: str | None = Field(None, description="Catalog folder; None = $ASSIST3D_ASSETS or the default cache folder, "
                                                  "falling back to the built-in procedural library.")
    procedural_count: int = Field(2000, ge=1, le=100_000, description="Assets in the built-in procedural library when "
                                                          "it is built on the fly, at most 100,000 (paper: ~50,000 "
                                                          "Objaverse models; n/a).")
    procedural_seed: int = Field(0, ge=0, le=2**32 - 1, description="Seed of the built-in procedural library "
                                                                    "(0..2^32-1).")


class RoomConfig(Section):
    """Room shell sampling (ScanNet-like rooms)."""

    area_min: float = Field(10.0, gt=0, le=1000, description="Smallest floor area, m^2, at most 1000 (ScanNet rooms: "
                                                             "~10-60 m^2).")
    area_max: float = Field(60.0, gt=0, le=1000, description="Largest floor area, m^2, at most 1000.")
    aspect_max: float = Field(2.0, ge=1, le=10, description="Largest ratio of the long to the short side, at most 10.")
    height_min: float = Field(2.4, gt=0, le=20, description="Lowest wall height, m, at most 20 (ScanNet: 2.4-3.2 m).")
    height_max: float = Field(3.2, gt=0, le=20, description="Highest wall height, m, at most 20.")
    l_shape_prob: float = Field(0.3, ge=0, le=1, description="Probability of an L-shaped footprint.")
    doors: tuple[int, int] = Field((1, 2), description="Inclusive range of door openings per room.")
    windows: tuple[int, int] = Field((0, 3), description="Inclusive range of window openings per room.")
    ceiling: bool = Field(False, description="Build a ceiling (real scans rarely capture it; off by default).")
    fill_openings: bool = Field(False, description="Put a labelled object in every opening, as real scans annotate "
                                "them: a door frame and leaf (closed or ajar into the door's clearance zone), a "
                                "window frame with mullion and sill; classes 'door' and 'window'.")


class SelectionConfig(Section):
    """Heterogeneous object selection (paper section 'Heterogeneous Object Selection')."""

    floor_count: int = Field(100, ge=0, le=10_000, description="M1: floor objects sampled per scene, at most 10,000 "
                                                               "(paper: 100).")
    wall_count: int = Field(50, ge=0, le=10_000, description="M2: wall objects sampled per scene, at most 10,000 "
                                                             "(paper: 50).")
    on_top_count: int = Field(5, ge=0, le=50, description="K: on-top objects sampled per floor/wall object, at most 50 "
                                                          "(paper: 5).")
    real_class_prob: float = Field(0.7, ge=0, le=1, description="p: probability a draw is restricted to the target "
                                                                 "real dataset's classes in complementary scenes "
                                                                 "(paper: 0.7).")
    complementary_fraction: float = Field(0.5, ge=0, le=1, description="Fraction of scenes using the complementary "
                                                                        "strategy; they alternate (paper: half).")
    real_classes: str = Field("scannet18", description="Target class list: 'scannet18', 'scannet200' or a path to a "
                                                        "text file with one class per line.")
    pairing_prob: float = Field(0.0, ge=0, le=1, description="q: probability to co-select a class's partner class "
                                                              "(context ablation; paper levels 1.0/0.66/0.33/0; "
                                                              "ASSIST-3D: 0).")
    clusters: list[int] | None = Field(None, description="Restrict selection to these shape-cluster ids "
                                                         "(geometry ablation; None = all).")
    allowed_classes: list[str] | None = Field(None, description="Only select assets of these classes (baselines such "
                                                                 "as holodeck-style; None = all).")
    assets_per_class: int | None = Field(None, ge=1, description="Keep only this many models of each class (a "
                                                                   "seeded, fixed choice), as a retrieval-based "
                                                                   "generator such as Holodeck does; None = all "
                                                                   "(ASSIST-3D).")
    max_classes: int | None = Field(None, ge=1, description="Restrict selection to this many classes "
                                                            "(scalability ablation: 100/200/400; None = all).")
    class_pool_seed: int = Field(0, ge=0, le=2**32 - 1, description="Seed fixing which classes survive max_classes "
                                                                    "and class pairing (0..2^32-1).")
    sampling: Literal["class", "asset"] = Field("class", description="'class': uniform over classes, then over "
                                                                      "the assets of the class (a class with many "
                                                                      "near-identical models does not dominate); "
                                                                      "'asset': uniform over assets (paper: "
                                                                      "uniform, unspecified).")
    strategy: Literal["heterogeneous", "room-type"] = Field(
        "heterogeneous", description="'heterogeneous': the paper's random draws (floor_count, wall_count, "
                                     "on_top_count per support); 'room-type': a Holodeck-style room: a room type "
                                     "drawn per scene and its typical object list with quantities "
                                     "(assist3d.core.taxonomy.roomtypes; floor_count and wall_count are then unused, "
                                     "on_top_count still applies).")
    room_types: list[str] | None = Field(None, description="Room types drawn from with strategy 'room-type' "
                                                           "(None = all of assist3d.core.taxonomy.roomtypes.ROOM_TEMPLATES).")
    on_top_fit: bool = Field(True, description="Draw a support's K on-top assets only among those whose box fits "
                                               "one of its surfaces (footprint, either way round, and clearance); "
                                               "paper: unspecified. False = the whole on-top pool.")
    min_real_classes: int = Field(3, ge=1, description="A complementary draw is restricted to real classes only when "
                                                       "the pool holds at least this many of them (else 70 % of, "
                                                       "say, on-top draws would be ScanNet18's lone 'picture'); "
                                                       "paper: n/a.")

    @field_validator("room_types")
    @classmethod
    def _known_room_types(cls, v: list[str] | None) -> list[str] | None:
        if v is not None:
            unknown = [t for t in v if t not in ROOM_TEMPLATES]
            if unknown or not v:
                raise ValueError(f"unknown room type(s) {unknown or v}; known: {', '.join(ROOM_TEMPLATES)}")
        return v


class LayoutConfig(Section):
    """Relation planning and depth-first placement (paper section 'Scene Layout Generation')."""

    planner: str = Field("rules", min_length=1, description="Relation planner: rules (default), llm (an "
                                                            "OpenAI-compatible LLM; paper: GPT-4), none (random "
                                                            "baseline), or any name registered in PLANNERS.")
    cell_size: float = Field(0.15, ge=0.01, le=2, description="Floor grid cell, m, 0.01..2 (paper: uniform grid; "
                                                              "0.1-0.25).")
    rotations: int = Field(4, ge=1, le=360, description="Yaw steps per full turn tried for each object (>= 4; at "
                                                        "most 360).")
    wall_step: float = Field(0.1, ge=0.01, le=2, description="Step along walls for wall objects, m, 0.01..2.")
    clearance: float = Field(0.02, ge=0, description="Minimum gap between objects, m.")
    door_clearance: float = Field(0.8, ge=0, description="Free depth kept in front of doors, m.")
    front_clearance: float = Field(0.3, ge=0, description="An object's front must be this far from walls, m.")
    group_budget_s: float = Field(4.0, gt=0, le=600, description="Wall-clock safety net of the search per group, s, "
                                                       "at most 600. The "
                                                       "deterministic limits below end the search long before it in "
                                                       "practice; if it ever binds, the layout depends on machine load "
                                                       "and a warning says so.")
    max_backtracks: int = Field(2000, ge=0, le=10**9, description="Backtracking steps per group before giving up "
                                                                  "(at most 1,000,000,000; group_budget_s ends any "
                                                                  "search).")
    max_nodes: int = Field(2000, ge=1, le=10**9, description="Candidate evaluations per group before backtracking "
                                                             "stops, at most 1,000,000,000 "
                                                   "(deterministic work budget; a 100-object floor group needs ~500).")
    max_on_top_per_support: int = Field(5, ge=0, le=50, description="On-top objects placed per support at most "
                                                                    "(0..50).")
    max_branch: int = Field(3, ge=1, le=100, description="Positions tried per object when the search backtracks "
                                                         "(at most 100): the best "
                                                 "one, then spread-out alternatives (paper: every valid cell; n/a).")
    patience: int = Field(20, ge=0, le=10**9, description="Backtracking steps (at most 1,000,000,000) without a "
                                                              "layout holding more objects before a "
                                                "group's search settles for its best (paper: n/a).")


class RenderConfig(Section):
    """Realistic point-cloud construction (paper section 'Realistic Point Cloud Construction')."""

    backend: str = Field("embree", min_length=1, description="Ray-casting backend: embree (fast, default), numpy "
                                                             "(slow, exact reference), or any name registered in "
                                                             "CASTERS.")
    vantage_points: int = Field(5, ge=1, le=100, description="Camera positions picked by farthest point sampling, at "
                                                             "most 100 (paper: 5).")
    views_per_point: int = Field(12, ge=1, le=360, description="Views per position, at most 360 (paper: 12 at "
                                                               "30-degree steps).")
    vantage_cell: float = Field(0.1, ge=0.01, le=2, description="Grid cell of the mid-height plane for vantage points, "
                                                                "m, 0.01..2 "
                                                       "(paper: 0.1).")
    vantage_clearance: float = Field(0.3, ge=0, description="Minimum distance of a vantage point to objects and "
                                                            "walls, m.")
    camera_height: float | None = Field(None, description="Camera height, m; None = mid-height of the room "
                                                          "(paper: mid-height plane).")
    pitch_deg: float | list[float] = Field([-30.0, 5.0], description="Camera pitch, degrees (negative looks down); a "
                                                                     "list cycles over the views of each vantage point. "
                                                                     "The paper does not state it; a level camera at "
                                                                     "mid-height sees no floor within ~3 m, so views "
                                                                     "alternate between looking down and level, as a "
                                                                     "hand-held scan does.")
    width: int = Field(640, ge=8, le=16384, description="Image width, px, 8..16384 (ScanNet depth: 640); with height, "
                                                        "views and voxel_size also bounded by a memory estimate that "
                                                        "refuses a run before it starts (assist3d.core.bounds).")
    height: int = Field(480, ge=8, le=16384, description="Image height, px, 8..16384 (ScanNet depth: 480).")
    fx: float = Field(577.9, gt=0, description="Focal length x, px (ScanNet depth ~577.9).")
    fy: float = Field(577.9, gt=0, description="Focal length y, px.")
    cx: float | None = Field(None, description="Principal point x, px; None = (width - 1) / 2.")
    cy: float | None = Field(None, description="Principal point y, px; None = (height - 1) / 2.")
    threads: int = Field(2, ge=1, le=256, description="Ray-casting threads, at most 256.")
    rays: Literal["full", "adaptive", "footprint"] = Field(
        "adaptive", description="Which rays a view casts: 'adaptive' (the default) = a lattice of every ray_tile-th "
                                "pixel, refined only where a tile's corner rays hit different triangles (edges, "
                                "the open sky); the other pixels' depths come from their triangle's plane, so the "
                                "view's pixels, and the points and labels fused from them, are those of the full "
                                "render up to rounding (docs/generation.md, 'Ray budget'); 'full' = one ray per "
                                "pixel (the reference, and the bytes of versions before the budget was the "
                                "default; a dataset whose config lacks the key was made with it); 'footprint' = "
                                "the adaptive lattice, stopped wherever it already samples every surface a tile "
                                "sees at most ray_spacing voxels apart, the pixels between left out (far fewer "
                                "rays and hits for almost the same occupied voxels; with depth-sensor options or "
                                "point_source 'tsdf', which need whole images, it renders as 'adaptive').")
    ray_tile: int = Field(8, ge=1, le=64, description="rays='adaptive' or 'footprint': lattice stride of the first "
                                                      "pass, px, a power of two at most 64 (1 = every pixel).")
    ray_spacing: float = Field(0.5, gt=0, le=4, description="rays='footprint': the largest distance between the "
                                                            "surface points of neighbouring kept pixels, in voxels, "
                                                            "above 0 and at most 4 (0.5 = 1 cm at 2 cm voxels).")
    voxel_size: float = Field(0.02, ge=0.001, le=1, description="Voxel downsampling size, m, 0.001..1 (paper: voxel "
                                                                "downsampling; "
                                                      "ScanNet-like 2 cm).")
    labels: Literal["ray", "nearest"] = Field("ray", description="Instance labels from the ray hit (exact) or the "
                                                                 "paper's nearest-object assignment.")
    nearest_radius: float = Field(0.05, gt=0, description="labels='nearest': points farther than this from every "
                                                          "object surface are background, m (paper: n/a; ~5 cm).")
    max_range: float | None = Field(None, description="Drop hits farther than this, m (sensor realism; off).")
    depth_noise: float = Field(0.0, ge=0, description="Depth noise std at 1 m, m, growing with distance^2 "
                                                      "(sensor realism; off).")
    grazing_dropout_deg: float | None = Field(None, description="Drop hits seen at more than this angle from the "
                                                                "normal, degrees (sensor realism; off).")
    edge_dropout: float = Field(0.0, ge=0, description="Drop pixels at depth edges with a jump above this, m "
                                                       "(sensor realism; 0 = off).")
    color_jitter: float = Field(0.0, ge=0, description="Std of per-view brightness jitter (sensor realism; off).")
    shading: bool = Field(True, description="Lambertian shading of colours by the view direction.")
    point_source: Literal["render", "mesh", "tsdf"] = Field(
        "render", description="'render': rendered RGB-D fusion, points are ray hits (paper); 'mesh': uniform mesh "
                              "sampling (ablation baseline); 'tsdf': ScanNet-like, the same views integrated into a "
                              "truncated signed distance field whose marching-cubes surface gives the points "
                              "(needs the [sim] extra: scikit-image).")
    tsdf_voxel: float = Field(0.02, ge=0.005, le=0.2, description="point_source='tsdf': TSDF voxel, m (ScanNet: 0.01; "
                                                              "coarser by default for CPU cost).")
    tsdf_trunc: float = Field(0.06, gt=0, le=1.0, description="point_source='tsdf': truncation at zero depth, m "
                                                              "(ScanNet: 0.06); at least tsdf_voxel.")
    tsdf_trunc_per_m: float = Field(0.02, ge=0, le=1.0, description="point_source='tsdf': truncation added per metre "
                                                                    "of depth, m/m (ScanNet: 0.02).")
    tsdf_max_depth: float = Field(10.0, gt=0, le=20.0, description="point_source='tsdf': deeper pixels are not "
                                                                   "integrated, m. ScanNet uses 4.0 with a handheld "
                                                                   "trajectory that passes near everything; from 5 fixed "
                                                                   "vantage points 4 m loses whole room corners.")
    tsdf_stride: int = Field(2, ge=1, le=16, description="point_source='tsdf': integrate every n-th pixel in x and "
                                                         "y (ScanNet integrates 640 x 480 depth at 320 x 240: 2).")
    tsdf_min_piece_m2: float = Field(0.05, ge=0, description="point_source='tsdf': connected surface pieces smaller "
                                                             "than this are dropped, m^2 (ScanNet drops pieces under "
                                                             "7,500 faces of its 1 cm mesh, ~0.4 m^2 of flat "
                                                             "surface; 0 = keep all).")

    @field_validator("ray_tile")
    @classmethod
    def _tile_power_of_two(cls, v: int) -> int:
        if v & (v - 1):
            raise ValueError(f"ray_tile must be a power of two (1, 2, 4, ... 64), not {v}")
        return v

    @model_validator(mode="after")
    def _tsdf_band_holds_a_voxel(self) -> "RenderConfig":
        if self.tsdf_trunc < self.tsdf_voxel:
            raise ValueError(f"tsdf_trunc ({self.tsdf_trunc}) must be at least tsdf_voxel ({self.tsdf_voxel})")
        return self


class LLMConfig(Section):
    """An OpenAI-compatible chat-completions endpoint (paper: GPT-4 for relations, GPT-4o for scores)."""

    base_url: str | None = Field(None, description="Endpoint base URL, e.g. https://api.openai.com/v1; None = off.")
    model: str | None = Field(None, description="Model name (paper: gpt-4 for relations).")
    vlm_model: str | None = Field(None, description="Vision model for layout scores (paper: gpt-4o); None = model.")
    temperature: float = Field(0.0, ge=0, le=2, description="Sampling temperature.")
    api_key_env: str = Field("OPENAI_API_KEY", description="Environment variable holding the API key (never stored).")
    timeout_s: float = Field(60.0, gt=0, le=3600, description="Per-request time-out, s, at most 3600.")
    retries: int = Field(2, ge=0, le=20, description="Retries after a failed request, with exponential back-off "
                                                     "(at most 20).")
    backoff_s: float = Field(1.0, ge=0, le=600, description="First back-off delay, s, at most 600.")
    max_response_bytes: int = Field(200_000, ge=1000, le=100_000_000, description="Larger answers are rejected "
                                                                                  "(at most 100,000,000 bytes).")
    max_tokens: int = Field(4096, ge=16, le=1_000_000, description="max_tokens sent with each request (at most "
                                                                   "1,000,000).")
    concurrency: int = Field(4, ge=1, le=256, description="Concurrent requests across all workers (at most 256).")
    plan_concurrently: bool = Field(True, description="Plan a scene's on-top groups at the same time (up to "
                                                      "`concurrency` requests) once its floor and wall objects are "
                                                      "placed; false = one group after another. The same answers "
                                                      "give the same layout either way.")
    on_top_batch: int = Field(1, ge=1, le=64, description="On-top groups asked for in one prompt: 1 = one prompt per "
                                                          "group; N > 1 = a scene's on-top groups N at a time (each "
                                                          "group's answer checked, repaired and, failing that, planned "
                                                          "by the rules on its own); at most 64.")
    answer_format: Literal["full", "compact"] = Field(
        "full", description="Form of the relation answers the prompts ask for: 'full' (an object per relation, "
                            "{\"relation\": ..., \"target\": ...}) or 'compact' ([index, \"edge\", [\"near\", 2]], "
                            "about a third of the tokens: faster and cheaper where answer time grows with "
                            "length). Either form is read in any answer; the prompts (and so the cache keys) differ.")
    scene_budget_s: float | None = Field(None, gt=0, le=86400, description="LLM planning time per scene, s: groups "
                                         "whose planning starts later are planned by the rules (recorded in "
                                         "layout.json); None = no limit; at most 86400.")
    cache_dir: str | None = Field(None, description="Response cache folder; None = <cache>/llm.")
    json_mode: bool = Field(True, description="Ask for response_format json_object (dropped silently when the "
                                              "server rejects it).")
    max_failures: int = Field(3, ge=1, le=1000, description="Consecutive endpoint failures (after retries, at most "
                                                            "1000) before the LLM "
                                                   "is skipped for 5 minutes and the rules take over.")
    prompt_dir: str | None = Field(None, description="Folder of edited prompt templates overriding the built-in "
                                                     "ones file by file; None = built-in.")


class OutputConfig(Section):
    """What the dataset writer produces."""

    ply: bool = Field(False, description="Also write points.ply coloured by instance.")
    save_mesh: bool = Field(False, description="Also write the assembled scene.glb.")


class GenerateConfig(Section):
    """Everything `assist3d generate` needs."""

    preset: str = Field("assist3d", description="Generator preset: assist3d, randomrooms, holodeck-style, no-context, "
                                                "or an ablation preset.")
    seed: int = Field(0, ge=0, le=2**32 - 1, description="Global seed, 0..2^32-1; scene k uses scene_seed(seed, k).")
    assets: AssetsConfig = Field(default_factory=AssetsConfig)
    room: RoomConfig = Field(default_factory=RoomConfig)
    selection: SelectionConfig = Field(default_factory=SelectionConfig)
    layout: LayoutConfig = Field(default_factory=LayoutConfig)
    render: RenderConfig = Field(default_factory=RenderConfig)
    llm: LLMConfig = Field(default_factory=LLMConfig)
    output: OutputConfig = Field(default_factory=OutputConfig)
