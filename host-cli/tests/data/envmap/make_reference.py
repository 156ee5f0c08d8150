# Mitsuba 3.9.1's render of scene.xml (scalar_rgb, two halves of 4096 spp with
# different seeds, and their mean): python3 make_reference.py. The scene's sky is the
# textured scene's, so the file is copied next to ../shared/scenes-extra/textured/ and
# loaded from there (optimize=False: see ../shared's note on 3.9.1's mesh merging).
import os, shutil, sys
import mitsuba as mi
mi.set_variant('scalar_rgb')
here = os.path.dirname(os.path.abspath(__file__))
textured = os.path.join(here, '../../../../../shared/scenes-extra/textured')
tmp = os.path.join('/tmp', 'ember-envmap-reference')
os.makedirs(os.path.join(tmp, 'textures'), exist_ok=True)
shutil.copy(os.path.join(textured, 'textures/sky.exr'), os.path.join(tmp, 'textures/sky.exr'))
shutil.copy(os.path.join(here, 'scene.xml'), os.path.join(tmp, 'scene.xml'))
scene = mi.load_file(os.path.join(tmp, 'scene.xml'), optimize=False)
halves = []
for seed, name in [(1, 'reference-half-a.exr'), (2, 'reference-half-b.exr')]:
    img = mi.render(scene, spp=4096, seed=seed)
    mi.Bitmap(img).write(os.path.join(here, name))
    halves.append(img)
mi.Bitmap((halves[0] + halves[1]) * 0.5).write(os.path.join(here, 'reference.exr'))
print('done')
sys.stdout.flush()
os._exit(0)  # 3.9.1's scalar variant can hang at interpreter exit
